// Contribution measure (the forward rasterizer's weights, maximum per Gaussian) and pruning by it.
#include "render/prune.h"

#include <torch/torch.h>

#include <algorithm>

#include "core/config.h"
#include "core/error.h"
#include "render/kernels.h"

namespace isplat {

void PruneOptions::visit(ConfigVisitor& v) {
  v.field("enabled", enabled, "drop Gaussians that contribute nothing visible after decoding");
  v.field("min_opacity", min_opacity, "drop Gaussians with opacity below this", Range::unit());
  v.field("min_contribution", min_contribution,
          "drop Gaussians whose largest rendered weight (alpha x transmittance) over the source view and the "
          "virtual views stays below this",
          Range::unit());
  v.field("views", views, "nearby virtual views besides the source: 0, 2 (+-x), 4 (+-x, +-y) or 6 (+-x, +-y, +-z)",
          Range::between(0, 6));
  v.field("view_shift", view_shift, "virtual camera offset as a fraction of the median Gaussian depth",
          Range::at_least(0.0));
  v.section("merge", "after the drops, merge flat single-coloured neighbours into one Gaussian", merge);
}

torch::Tensor max_contribution(const Gaussians& g, const Camera& camera, const RenderOptions& options) {
  ISPLAT_CHECK(!g.batched() && camera.batch() == 0, "max_contribution: takes one unbatched set and camera");
  torch::NoGradGuard no_grad;
  const auto dtype = g.means.scalar_type();
  ISPLAT_CHECK(dtype == torch::kFloat32 || dtype == torch::kFloat64,
               "max_contribution: Gaussians must be float32 or float64, got ", dtype);
  const int64_t n = g.count();
  auto flat = [&](const torch::Tensor& t, int64_t cols) {
    ISPLAT_CHECK(t.defined() && t.numel() == n * std::max<int64_t>(cols, 1), "max_contribution: a Gaussian tensor ",
                 t.defined() ? t.sizes() : c10::IntArrayRef{}, " does not match ", n, " means");
    return (cols == 0 ? t.reshape({n}) : t).detach().to(dtype).contiguous();
  };
  const splat::CameraParams cam =
      splat::camera_params(camera.K, camera.T_cw, camera.width, camera.height, /*validate=*/true);
  const splat::ProjectSettings ps{options.near, options.dilation, options.antialiased};
  const splat::Projection proj = splat::project_fwd(flat(g.means, 3), flat(g.scales, 3), flat(g.quats, 4),
                                                    flat(g.colors, 3), flat(g.opacities, 0), cam, ps);
  const splat::TileBins bins = splat::bin_tiles(proj, cam);
  return splat::rasterize_max_weight(proj.packed, bins, cam);
}

std::vector<Camera> nearby_views(const Camera& source, double shift, int64_t views) {
  ISPLAT_CHECK(source.batch() == 0, "nearby_views: takes one unbatched camera");
  ISPLAT_CHECK(views >= 0 && views <= 6, "nearby_views: views must be in [0, 6], got ", views);
  std::vector<Camera> out;
  for (int64_t k = 0; k < views; ++k) {
    Camera c = source;
    c.T_cw = source.T_cw.clone();
    // x_cam = R x + t: moving the camera centre by +d along its own axis a subtracts d from t[a].
    const int64_t axis = k / 2;
    const double d = (k % 2 == 0 ? 1.0 : -1.0) * shift;
    c.T_cw.index_put_({axis, 3}, c.T_cw.index({axis, 3}) - d);
    out.push_back(c);
  }
  return out;
}

// Whether each Gaussian reaches min_contribution in the source view or one of the nearby virtual views.
static torch::Tensor visible_in_views(const Gaussians& g, const Camera& source, const PruneOptions& o,
                                      const RenderOptions& render_options) {
  torch::Tensor best = max_contribution(g, source, render_options);
  if (o.views > 0) {
    // Median depth of the Gaussians in the source camera sets the scale of the virtual moves.
    const auto T = source.T_cw.to(g.means.scalar_type());
    const auto z = torch::matmul(g.means.detach(), T.index({2, torch::indexing::Slice(0, 3)})) + T.index({2, 3});
    const double shift = o.view_shift * std::max(0.0, z.median().item<double>());
    for (const Camera& c : nearby_views(source, shift, o.views))
      best = torch::maximum(best, max_contribution(g, c, render_options));
  }
  return best >= o.min_contribution;
}

std::map<std::string, int64_t> prune_counts(const PruneResult& r) {
  return {{"low_opacity", r.low_opacity},
          {"low_contribution", r.low_contribution},
          {"merged_groups", r.merge.groups},
          {"merged_members", r.merge.members},
          {"refused_color", r.merge.refused_color},
          {"refused_shape", r.merge.refused_shape},
          {"refused_normal", r.merge.refused_normal},
          {"alone", r.merge.alone}};
}

PruneResult prune_gaussians(const Gaussians& g, const Camera& source, const PruneOptions& o,
                            const RenderOptions& render_options) {
  torch::NoGradGuard no_grad;
  PruneResult r;
  r.before = g.count();
  r.keep = torch::ones({r.before}, torch::kBool);
  if (!o.enabled || r.before == 0) {
    r.kept = g;
    return r;
  }
  const torch::Tensor opaque = g.opacities.detach().reshape({r.before}) >= o.min_opacity;
  r.low_opacity = r.before - opaque.sum().item<int64_t>();
  if (o.min_contribution <= 0) {  // nothing can fall below it: skip the renders
    r.keep = opaque;
  } else {
    r.keep = opaque.logical_and(visible_in_views(g, source, o, render_options));
    r.low_contribution = opaque.sum().item<int64_t>() - r.keep.sum().item<int64_t>();
  }
  r.kept = g.index(r.keep);
  const MergeResult merged = merge_gaussians(r.kept, source, o.merge);
  r.kept = merged.merged;
  r.merge = merged;
  return r;
}

}  // namespace isplat
