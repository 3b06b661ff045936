// Scores by image region and in the source view, for the breakdown that shows where a method's error lives.
#include "eval/region_scores.h"

#include <limits>

#include "metrics/regions.h"

namespace isplat {

namespace {
RegionScore region_score(const torch::Tensor& image, const torch::Tensor& target, const torch::Tensor& region,
                         const Gaussians& scene, const Camera& camera, const Lpips* lpips, double share) {
  RegionScore g;
  g.share = share;
  if (!(region.sum().item<double>() > 0)) return g;
  g.psnr = psnr(image, target, region);
  if (lpips) g.lpips = (*lpips)(image, target, region);
  g.detail = detail_ratio(image, target, region);
  if (scene.means.defined()) g.density = centre_density(scene.means, camera, region);
  return g;
}
}  // namespace

void score_regions(const MethodOutput& o, const ViewTensors& source, const ViewTensors& target,
                   const torch::Tensor& mask, const torch::Tensor& ref_depth, const Lpips* lpips,
                   const RenderOptions& render_options, PairResult& r) {
  const auto scored = (mask > 0).to(torch::kFloat32);
  const double pixels = scored.sum().item<double>();
  r.regions["all"] = region_score(o.image, target.image, scored, o.scene, target.camera, lpips, 1.0);
  for (const auto& [name, region] : image_regions(target.image, ref_depth, scored))
    r.regions[name] = region_score(o.image, target.image, region, o.scene, target.camera, lpips,
                                   pixels > 0 ? region.sum().item<double>() / pixels : 0.0);
  if (!o.scene.means.defined()) return;
  const RenderOutput back = render(o.scene, source.camera, render_options, RenderMaps::colour_only());
  // Where the source has depth: pixels without it (a sky, a window) get no supports by design in every method.
  const auto scored_source = source.valid.defined() && source.valid.sum().item<double>() > 0
                                 ? (source.valid > 0).to(torch::kFloat32)
                                 : torch::ones({source.camera.height, source.camera.width});
  r.source_view = region_score(rendered_srgb(back.rgb, o.linear_rgb), source.image, scored_source, o.scene,
                               source.camera, lpips, 1.0);
}

}  // namespace isplat
