// Pruning after decoding: drop Gaussians that are nearly transparent or never contribute a visible weight
// (α·T) to the source view or to a few nearby virtual views, then optionally merge flat single-coloured
// neighbours, so a scene keeps only the Gaussians it needs.
#pragma once
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <torch/types.h>

#include "core/gaussians.h"
#include "geometry/camera_torch.h"
#include "render/merge.h"
#include "render/render.h"

namespace isplat {

class ConfigVisitor;

struct PruneOptions {
  bool enabled = false;
  double min_opacity = 0.005;      // drop Gaussians with opacity below this
  double min_contribution = 0.01;  // drop Gaussians whose largest α·T over the views stays below this
  int64_t views = 4;               // virtual views besides the source: 0, 2 (±x), 4 (±x, ±y) or 6 (±x, ±y, ±z)
  double view_shift = 0.1;         // virtual camera offset as a fraction of the median Gaussian depth
  MergeOptions merge;              // after the drops: merge flat single-coloured neighbours (off by default)
  void visit(ConfigVisitor& v);
};

// Per Gaussian [N] (unbatched set, one unbatched camera): the largest weight α·T it reaches at any pixel
// of the view, with the renderer's own rules (culling, skip and stop thresholds). No gradient.
torch::Tensor max_contribution(const Gaussians& gaussians, const Camera& camera, const RenderOptions& options = {});

// The source camera moved by `shift` metres along its own ±x, then ±y, then ±z axes: the first `views`.
std::vector<Camera> nearby_views(const Camera& source, double shift, int64_t views);

struct PruneResult {
  Gaussians kept;
  torch::Tensor keep;  // [N] bool: what survived the drops (merging then acts on those)
  int64_t before = 0, low_opacity = 0, low_contribution = 0;
  MergeCounts merge;  // merge.removed(): Gaussians removed by merging
  int64_t after() const { return before - low_opacity - low_contribution - merge.removed(); }
};

// The counts by name, for logs: low_opacity, low_contribution, merged_groups, merged_members, refused_color,
// refused_shape, refused_normal, alone.
std::map<std::string, int64_t> prune_counts(const PruneResult& result);

// Applies the options (when disabled, keeps everything): the drops, then merging. `source` is the camera the set was
// predicted in.
PruneResult prune_gaussians(const Gaussians& gaussians, const Camera& source, const PruneOptions& options,
                            const RenderOptions& render_options = {});

}  // namespace isplat
