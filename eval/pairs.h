// The paper's pair protocol (DESIGN §5): directed source -> target pairs within windows of 10 consecutive
// views, filtered by frustum overlap and rotation, binned by baseline, drawn under a fixed seed with a
// per-scene cap, and written to a manifest that every method is scored on.
#pragma once
#include <array>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "data/colmap.h"
#include "data/sequence.h"

namespace isplat {

class ConfigVisitor;

struct ProtocolOptions {
  int64_t window = 10;                                   // consecutive views per window
  double min_overlap = 0.6;                              // frustum overlap of the source depth in the target
  double max_rotation_deg = 60.0;                        // angle between optical axes; >= 90 is backward-facing
  std::vector<double> bin_edges = {0.0, 0.5, 1.0, 2.0};  // metres; the last bin is open: [2, inf)
  int64_t pairs_per_bin = 128;
  int64_t per_scene_cap = 32;  // at most this many pairs per scene in each bin
  int64_t seed = 0;
  // Overlap depth for frames without depth and without usable COLMAP points3D: metres, or 0 = from the
  // cameras (the median depth at which neighbouring optical axes converge).
  double fallback_depth = 0.0;
  void visit(ConfigVisitor& v);
};

struct Pair {
  std::string dataset, scene, sequence;
  size_t sequence_index = 0;      // into the dataset's sequence list
  size_t source = 0, target = 0;  // frame indices in the sequence
  std::string source_name, target_name;
  double baseline = 0, overlap = 0, rotation_deg = 0;
  int bin = 0;
  std::string overlap_depth =
      "dataset";  // what the overlap test used: dataset | points3d | scene-points3d | fixed | camera-axes
};

struct Manifest {
  std::string dataset;
  ProtocolOptions protocol;
  std::vector<Pair> pairs;
  std::vector<int64_t> bin_counts;      // filled per bin
  std::vector<int64_t> bin_candidates;  // candidates available per bin (after filters)
  // Why candidate pairs were dropped: "rotation", "overlap", "outside bins", "per-scene cap", and
  // "source without depth" (frames skipped).
  std::map<std::string, int64_t> rejected;
  std::map<std::string, int64_t> overlap_depth;  // source frames per overlap-depth kind
  // What the pairs were drawn from (eval/datasets.h dataset_fingerprint); null in manifests written before it.
  nlohmann::json dataset_fingerprint;
  // One sentence on why `bin` has fewer pairs than requested, naming the dominant cause.
  std::string shortfall_reason(int bin) const;
  nlohmann::ordered_json to_json() const;
  static Manifest from_json(const nlohmann::json& j, const std::string& source);
  std::string bin_label(int b) const;  // "[0.5,1)" or "[2,inf)"
};

// Depth for the frustum-overlap test of a source frame. Frames with depth use it; frames without use,
// in order: the COLMAP points3D the view observes (a coarse map of their depths, empty cells at the view's
// median point depth), the scene's median point depth, protocol.fallback_depth, or the depth at which
// neighbouring optical axes converge. `kind` names the one used.
struct OverlapDepth {
  DepthMap map;
  std::string kind;
};
class OverlapDepthSource {
 public:
  // `model`: the sequence's COLMAP model, or nullptr (nerfstudio, or no points).
  OverlapDepthSource(const Sequence& sequence, const ColmapModel* model, const ProtocolOptions& options);
  OverlapDepth for_frame(size_t index) const;

 private:
  const Sequence& sequence_;
  std::vector<std::vector<Eigen::Vector3d>> points_;  // per frame: (u, v, z) of observed points
  double scene_depth_ = 0, fallback_ = 0;
  std::string fallback_kind_;
};

// Scores every candidate pair (frame depth is loaded once per source frame) and draws the manifest.
// Bins that cannot be filled keep what they have, and the manifest says so; they are never padded.
// `models` (optional, one per sequence) gives depth-free COLMAP captures their points3D for the overlap.
Manifest draw_manifest(const std::string& dataset, const std::vector<Sequence>& sequences,
                       const ProtocolOptions& options, const std::vector<ColmapModel>& models = {});

// The kind of viewpoint change of a pair, by which moves the image most (in normalized image units):
// "lateral" (translation across the view, |t_xy| / z), "forward" (along the optical axis, x·|t_z| / z
// for a point at normalized offset x = `half_edge`, half-way to the frame edge: (W/4)/fx) or "rotation"
// (the angle between optical axes, radians). `t` is the target camera's centre in the source camera
// frame, `z` the source's median depth (same units).
std::string motion_type(const std::array<double, 3>& t, double rotation_deg, double median_depth,
                        double half_edge = 0.5);

void write_manifest(const std::string& path, const Manifest& m);  // atomic; byte-identical for equal input
Manifest read_manifest(const std::string& path);

}  // namespace isplat
