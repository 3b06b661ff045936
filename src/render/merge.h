// Merging after decoding: neighbouring Gaussians that form one flat patch of one colour become one Gaussian
// with the same first and second moments, so a plain wall keeps fewer Gaussians than a cluttered shelf.
#pragma once
#include <cstdint>
#include <string>

#include <torch/types.h>

#include "core/gaussians.h"
#include "geometry/camera_torch.h"

namespace isplat {

class ConfigVisitor;

struct MergeOptions {
  double cell_px = 0;           // grouping cell in source pixels (0 = off)
  double max_color = 0.03;      // largest per-channel distance of a member's colour (as stored) from the group's mean
  double max_flatness = 0.25;   // largest thickness / narrower width of the merged Gaussian (keeps depth edges apart)
  double min_normal_cos = 0.9;  // flat members' normals must agree with the merged normal this well
  bool split = false;           // a cell refused whole merges each of its single-coloured parts on its own
  void visit(ConfigVisitor& v);
};

// What merging did, also carried by PruneResult.
struct MergeCounts {
  int64_t groups = 0;   // groups (cells, or parts of split cells) that became one Gaussian
  int64_t members = 0;  // Gaussians those groups held
  // Groups refused, by the first test they failed (diagnostics; a split cell can count more than once).
  int64_t refused_color = 0, refused_shape = 0, refused_normal = 0;
  int64_t alone = 0;  // Gaussians with no other in their cell (or behind the camera): nothing to merge with
  int64_t removed() const { return members - groups; }
};

struct MergeResult : MergeCounts {
  Gaussians merged;
  int64_t before = 0;
};

// Groups an unbatched set by the source-view cell its mean projects into. A cell of two or more Gaussians is
// replaced by one when every member's colour is within max_color of the mean, the merged Gaussian
// is flat and every flat member lies in its plane (normals within min_normal_cos). The merged Gaussian has the
// members' weighted mean, colour, opacity and covariance (each member weighted by opacity times its footprint area),
// with its two in-plane axes grown (never shrunk) so that its opacity times area equals the members' total. Gaussians
// behind the camera stay as they are. With `split`, a cell refused whole merges each single-coloured part on its own.
// No gradient. With cell_px = 0 the set is returned unchanged.
MergeResult merge_gaussians(const Gaussians& gaussians, const Camera& source, const MergeOptions& options);

}  // namespace isplat
