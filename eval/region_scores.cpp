// Scores by image region and in the source view, for the breakdown that shows where a method's error lives.
#include "eval/region_scores.h"

#include <limits>
#include <vector>

#include "metrics/regions.h"

namespace isplat {

namespace {
// lpips_maps: Lpips::distance_maps of image and target, computed once for all of a view's regions (empty: no LPIPS).
RegionScore region_score(const torch::Tensor& image, const torch::Tensor& target, const torch::Tensor& region,
                         const Gaussians& scene, const Camera& camera, const std::vector<torch::Tensor>& lpips_maps,
                         double share) {
  RegionScore g;
  g.share = share;
  if (!(region.sum().item<double>() > 0)) return g;
  g.psnr = psnr(image, target, region);
  if (!lpips_maps.empty()) g.lpips = Lpips::mean_distance(lpips_maps, region);
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
  const auto maps = lpips ? lpips->distance_maps(o.image, target.image) : std::vector<torch::Tensor>{};
  r.regions["all"] = region_score(o.image, target.image, scored, o.scene, target.camera, maps, 1.0);
  for (const auto& [name, region] : image_regions(target.image, ref_depth, scored))
    r.regions[name] = region_score(o.image, target.image, region, o.scene, target.camera, maps,
                                   pixels > 0 ? region.sum().item<double>() / pixels : 0.0);
  if (!o.scene.means.defined()) return;
  const RenderOutput back = render(o.scene, source.camera, render_options, RenderMaps::colour_only());
  // Where the source has depth: pixels without it (a sky, a window) get no supports by design in every method.
  const auto scored_source = source.valid.defined() && source.valid.sum().item<double>() > 0
                                 ? (source.valid > 0).to(torch::kFloat32)
                                 : torch::ones({source.camera.height, source.camera.width});
  const auto image = rendered_srgb(back.rgb, o.linear_rgb);
  const auto source_maps = lpips ? lpips->distance_maps(image, source.image) : std::vector<torch::Tensor>{};
  r.source_view = region_score(image, source.image, scored_source, o.scene, source.camera, source_maps, 1.0);
}

}  // namespace isplat
