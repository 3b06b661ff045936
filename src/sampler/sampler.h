// Geometry-guided support sampling on the back-projected depth surface (DESIGN §3): supports are placed
// in proportion to 3D triangle area, not on the pixel grid; plus the pixel and vertex+face modes.
#pragma once
#include <cstdint>
#include <string>

#include <torch/types.h>

namespace isplat {

class ConfigVisitor;

// Upper bound on any support budget: 4M is the paper's 1.5M with room; 2e7 ran 4.5 min at 9.3 GB.
constexpr int64_t kMaxSupports = 4000000;

// The paper release's sampler; the model's defaults (ModelOptions, model/infinisplat.h) are the lab's recipe:
// pixel mode with edge_shift and edge_behind.
struct SamplerOptions {
  std::string mode = "area";          // area | pixel | vertex_face
  std::string budget_mode = "fixed";  // fixed | per_pixel | solid_angle | detail
  int64_t budget = 100000;            // supports, for budget_mode "fixed"
  double density = 1.0;               // supports per image pixel (per_pixel) or per steradian (solid_angle)
  int64_t min_budget = 1000, max_budget = 4000000;
  double vertex_fraction = 0.65;  // vertex_face: share of the budget spent on gradient-priority vertices
  // budget_mode "detail": a block of detail_block² pixels gets density · (floor + (1 − floor)·min(1, d/ref))
  // supports per pixel, d its mean detail (colour gradient + curvature of the surface); area mode places them
  // in proportion to area × that weight, so flat, plain regions get few and cluttered ones many.
  double detail_floor = 0.15, detail_ref = 0.05;
  int64_t detail_block = 8;
  // area mode: share of the budget spread evenly over the image's accepted triangles (each pixel alike)
  // instead of by 3D area, so near surfaces, whose pixels cover little area, are not starved. 0 = paper.
  double image_share = 0.0;
  // area mode: a floor under each triangle's measure, as a share of the even per-pixel spread (0 = off).
  double pixel_floor = 0.0;
  // area mode: one support at the centre of every valid pixel that no accepted triangle surrounds (depth
  // edges, holes, the image border), taken from the budget; faces get the rest.
  bool edge_supports = false;
  // With edge_supports: valid pixels up to this many steps into the near side of a depth edge, over their own surface
  // (steps that cross no discontinuity), get a pixel-centre support too, and triangles wholly inside that band get
  // none, so silhouettes sit on pixel rays as in pixel mode while surfaces keep area sampling; far sides, holes and
  // the border keep faces up to their edge supports (lab/2026-11-28-behind-band). 0 = only the edge pixels.
  int64_t edge_band = 0;
  // With edge_supports (or in pixel mode): supports on the near side of a depth edge sit this many pixels from their
  // pixel centre, away from the farther neighbours (same depth, colour and footprint). 0 = at the centre.
  double edge_shift = 0.0;
  // With edge_supports (or in pixel mode, on top of one per pixel): supports that continue the farther surface under
  // each near-side silhouette pixel, up to this many pixels deep while they stay hidden in the source view (on the
  // farther neighbours' surfaces extrapolated as planes, in their colour). 0 = off.
  int64_t edge_behind = 0;
  // Before sampling, invalid pixels within this many pixels of valid depth get depth filled in from around them
  // (sampler/depth_fill.h), so small holes in the depth get supports. 0 = off (the paper: supports only where
  // depth is).
  int64_t fill_px = 0;
  void visit(ConfigVisitor& v);
  // Whether the mode places a budget of supports (pixel mode: one per valid pixel, whatever the budget keys say).
  bool has_budget() const;
};

// Supports in the source camera. Depth and colour are read bilinearly at uv (barycentric inside a triangle
// whose quad neighbour was rejected, so values never mix across a depth discontinuity).
struct Supports {
  torch::Tensor uv;      // [N,2] continuous pixel coordinates (pixel centres at +0.5)
  torch::Tensor depth;   // [N] planar metres
  torch::Tensor color;   // [N,3] sRGB in [0,1]
  torch::Tensor area;    // [N] surface area each support stands for, m² (area mode: total / N)
  torch::Tensor normal;  // [N,3] unit surface normal in the camera frame, facing the camera; only when asked (normals)
  int64_t behind = 0;    // the last `behind` supports are hidden surface under near-side silhouettes (edge_behind)
  int64_t count() const { return uv.size(0); }
};

// The number of supports the options ask for on this depth map (valid: [H,W] 0/1, K: [3,3]; image [3,H,W]
// sRGB, needed by budget_mode "detail" only).
int64_t resolve_budget(const SamplerOptions& options, const torch::Tensor& depth, const torch::Tensor& valid,
                       const torch::Tensor& K, const torch::Tensor& image = {});

// budget_mode "detail": the per-pixel weight in [detail_floor, 1] ([H,W] float, 0 where depth is unusable).
torch::Tensor detail_weights(const torch::Tensor& depth, const torch::Tensor& valid, const torch::Tensor& image,
                             const SamplerOptions& options);

// depth [H,W] float (planar metres), valid [H,W] (nonzero = valid), K [3,3], image [3,H,W] sRGB.
// Deterministic in `seed`; the count equals the resolved budget (pixel mode: one per valid pixel).
// Throws Error when no triangle (or pixel) is valid. `normals` fills Supports::normal: the model asks for them only
// when composer.orientation = surface reads them; nearly free at 2 supports per pixel, about a third more at 1.5M.
Supports sample_supports(const torch::Tensor& depth, const torch::Tensor& valid, const torch::Tensor& K,
                         const torch::Tensor& image, const SamplerOptions& options, uint64_t seed = 0,
                         bool normals = false);

// The release's discontinuity test: a triangle is rejected when zmax/zmin >= this threshold.
double discontinuity_threshold(double z_mean);

// That test for two depths: true when they lie on different surfaces (max/min >= the threshold at their mean).
bool depths_apart(double a, double b);

}  // namespace isplat
