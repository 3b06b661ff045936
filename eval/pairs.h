// The paper's pair protocol (DESIGN §5): directed source -> target pairs within windows of 10 consecutive
// views, filtered by frustum overlap and rotation, binned by baseline, drawn under a fixed seed with a
// per-scene cap, and written to a manifest that every method is scored on.
#pragma once
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

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
  void visit(ConfigVisitor& v);
};

struct Pair {
  std::string dataset, scene, sequence;
  size_t sequence_index = 0;      // into the dataset's sequence list
  size_t source = 0, target = 0;  // frame indices in the sequence
  std::string source_name, target_name;
  double baseline = 0, overlap = 0, rotation_deg = 0;
  int bin = 0;
};

struct Manifest {
  std::string dataset;
  ProtocolOptions protocol;
  std::vector<Pair> pairs;
  std::vector<int64_t> bin_counts;      // filled per bin
  std::vector<int64_t> bin_candidates;  // candidates available per bin (after filters)
  nlohmann::ordered_json to_json() const;
  static Manifest from_json(const nlohmann::json& j, const std::string& source);
  std::string bin_label(int b) const;  // "[0.5,1)" or "[2,inf)"
};

// Scores every candidate pair (frame depth is loaded once per source frame) and draws the manifest.
// Bins that cannot be filled keep what they have, and the manifest says so; they are never padded.
Manifest select_pairs(const std::string& dataset, const std::vector<Sequence>& sequences,
                      const ProtocolOptions& options);

void write_manifest(const std::string& path, const Manifest& m);  // atomic; byte-identical for equal input
Manifest read_manifest(const std::string& path);

}  // namespace isplat
