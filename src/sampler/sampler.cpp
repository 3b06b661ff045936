// The sampler's entry points: the options' schema, and sample_supports, which fills holes, builds the triangle grid,
// resolves the budget and hands the rest to the strategy that sampler.mode names (sampler/strategy.h).
#include "sampler/sampler.h"

#include <torch/torch.h>

#include "core/config.h"
#include "core/error.h"
#include "sampler/budget.h"
#include "sampler/strategy.h"

namespace isplat {

void SamplerOptions::visit(ConfigVisitor& v) {
  v.field("mode", mode,
          "support placement: one per pixel centre (the default, with edge_behind's hidden surface; the budget keys "
          "do not apply), area-weighted on the depth surface (paper), or the release's gradient-priority vertices + "
          "area-weighted faces",
          {"area", "pixel", "vertex_face"});
  v.field("budget_mode", budget_mode,
          "fixed count; or per image pixel, per steradian of valid surface; or detail: per pixel, scaled by how "
          "much the image and surface vary there (see detail_floor)",
          {"fixed", "per_pixel", "solid_angle", "detail"});
  v.field("budget", budget, "number of supports when budget_mode = fixed (paper: 1.5M at 1536x1024)",
          Range::between(1, kMaxSupports));
  v.field("density", density, "supports per pixel (per_pixel) or per steradian (solid_angle)", Range::above(0));
  v.field("min_budget", min_budget, "lower bound for adaptive budgets", Range::between(1, kMaxSupports));
  v.field("max_budget", max_budget, "upper bound for adaptive budgets", Range::between(1, kMaxSupports));
  v.require("max_budget", min_budget <= max_budget, "must be >= sampler.min_budget");
  v.field("vertex_fraction", vertex_fraction, "vertex_face: fraction of supports on gradient-priority vertices",
          Range::unit());
  v.field("detail_floor", detail_floor,
          "detail budget: share of `density` a featureless, flat block gets (1 = per_pixel everywhere)",
          Range::between(0.01, 1.0));
  v.field("detail_ref", detail_ref,
          "detail budget: block detail (mean colour gradient + surface curvature per pixel) that earns the full "
          "density",
          Range::above(0.0));
  v.field("detail_block", detail_block, "detail budget: block size in pixels over which detail is averaged",
          Range::between(1, 256));
  v.field("image_share", image_share,
          "area mode: share of supports spread evenly per image pixel instead of by 3D area (0 = the paper's "
          "area sampling; near surfaces get more supports as it grows)",
          Range::unit());
  v.field("pixel_floor", pixel_floor,
          "area mode: no accepted triangle draws supports below this share of an even per-pixel spread (applied "
          "after image_share), so near surfaces keep at least that density; the rest still follows area (0 = off)",
          Range::between(0.0, 4.0));
  v.field("edge_supports", edge_supports,
          "area mode: also one support per valid pixel at a depth edge, hole or image border (where no accepted "
          "triangle surrounds it and faces leave a half-pixel gap), taken from the budget");
  v.field("edge_band", edge_band,
          "area mode with edge_supports: pixels up to this many steps into the near side of a depth edge, over "
          "their own surface, get a pixel-centre support too and triangles wholly inside the band get none "
          "(silhouettes on pixel rays, area sampling elsewhere; far sides, holes and the border keep faces up to "
          "their edge supports); 0 = the edge pixels only",
          Range::between(0, 16));
  v.require("edge_band", edge_band == 0 || edge_supports, "needs sampler.edge_supports = true");
  v.field("edge_shift", edge_shift,
          "area mode with edge_supports, or pixel mode: move each support at a depth edge's near side (area: the "
          "edge supports) this many pixels away from the farther surface, keeping its depth, colour and footprint, "
          "so silhouettes spill less onto the background (0 = at the pixel centre)",
          Range::between(0.0, 0.5));
  // edge_shift and edge_behind act on the supports at depth edges: every pixel's in pixel mode, the edge supports in
  // area mode (with a band, its pixels beside a depth edge: band supports are a pixel apart, so a near-side one moved
  // half a pixel in still overlaps the next).
  const bool at_edges = mode == "pixel" || (mode == "area" && edge_supports);
  const char* at_edges_needs =
      "needs sampler.mode = pixel, or sampler.mode = area with sampler.edge_supports = true (it acts on the supports "
      "at depth edges)";
  v.require("edge_shift", edge_shift == 0.0 || at_edges, at_edges_needs);
  v.field("edge_behind", edge_behind,
          "area mode with edge_supports, or pixel mode: continue the farther surface under each near-side "
          "silhouette pixel with up to this many supports, one pixel apart inwards while they stay hidden, on the "
          "farther neighbours' surfaces extrapolated as planes, in their colour, so what a new view uncovers beside "
          "a silhouette has surface (area mode: taken from the budget, at most half of it with the edge supports; "
          "pixel mode: on top of one per pixel; 0 = off)",
          Range::between(0, 4));
  v.require("edge_behind", edge_behind == 0 || at_edges, at_edges_needs);
  v.field("fill_px", fill_px,
          "before sampling, fill invalid depth within this many pixels of valid depth (push-pull in log depth), so "
          "small holes (sensor drop-outs, invalid prior pixels) get supports; the inside of larger missing regions "
          "(most of a sky) stays empty; 0 = off",
          Range::between(0, 256));
}

namespace sampling {

std::unique_ptr<SupportStrategy> make_area_strategy();
std::unique_ptr<SupportStrategy> make_pixel_strategy();
std::unique_ptr<SupportStrategy> make_vertex_face_strategy();

std::unique_ptr<SupportStrategy> make_support_strategy(const std::string& mode) {
  if (mode == "area") return make_area_strategy();
  if (mode == "pixel") return make_pixel_strategy();
  if (mode == "vertex_face") return make_vertex_face_strategy();
  fail("sampler.mode: unknown '", mode, "' (area | pixel | vertex_face)");
}

}  // namespace sampling

bool SamplerOptions::has_budget() const {
  return sampling::make_support_strategy(mode)->uses_budget();
}

using namespace sampling;

Supports sample_supports(const torch::Tensor& depth, const torch::Tensor& valid, const torch::Tensor& K,
                         const torch::Tensor& image, const SamplerOptions& options, uint64_t seed, bool normals) {
  torch::NoGradGuard no_grad;
  if (options.fill_px > 0) {
    const FilledDepth f = fill_holes(depth, valid, options);
    return sample_supports(f.depth, f.valid, K, image, without_fill(options), seed, normals);
  }
  torch::Tensor dk, vk, ik;
  const Grid g = make_grid(depth, valid, K, image, dk, vk, ik);
  const std::unique_ptr<SupportStrategy> strategy = make_support_strategy(options.mode);
  std::vector<float> weight;
  int64_t n = 0;
  if (strategy->uses_budget()) {
    if (options.budget_mode == "detail") weight = detail_weights(g, options);
    n = weight.empty() ? resolve_budget(options, dk, vk, K) : detail_budget(options, weight);
  }
  return strategy->sample({g, options, n, &weight, seed, normals});
}

}  // namespace isplat
