// Perturbations of a source view: depth errors (global scale, multiplicative noise, a smooth warp, blur, holes,
// noise or drop-outs at depth edges, depth on one side only) and image changes (exposure, JPEG), for the stability
// suite; and random depth errors drawn per tuple for training. Deterministic for a seed.
#pragma once
#include <cstdint>
#include <string>

#include "data/sensor.h"
#include "data/tuples.h"

namespace isplat {

class ConfigVisitor;

struct PerturbOptions {
  double depth_scale = 1.0;       // global scale error: z·s
  double depth_noise = 0.0;       // multiplicative noise sigma on every pixel: z(1 + ε), ε ~ N(0, σ²)
  double depth_warp = 0.0;        // smooth shape error: z·exp(σ·f), f bilinear between N(0, 1) grid nodes
  int64_t depth_warp_cells = 3;   // ... with this many grid cells across the width
  double depth_blur_px = 0.0;     // Gaussian blur sigma of the depth map, pixels (valid pixels only)
  double depth_holes = 0.0;       // share of valid depth pixels made invalid
  double depth_hole_size = 8.0;   // ... as blobs of about this radius (pixels); 0 = independent pixels
  double depth_edge_noise = 0.0;  // multiplicative noise sigma at depth edges only
  int64_t depth_edge_holes = 0;   // depth within this many pixels (Chebyshev) of a depth edge made invalid
  std::string depth_edge_holes_side = "both";  // ... on both sides, or "far": only behind the nearer surface
  std::string depth_side = "all";              // all | left | right | top | bottom: depth (and prompts) only there
  double exposure = 1.0;                       // source image scaled by this in linear light
  int64_t jpeg_quality = 0;                    // 0 = off; else the source image re-encoded as JPEG at this quality
  SensorOptions sensor;                        // a depth sensor's errors (data/sensor.h), after depth_edge_holes
  bool any() const;
  bool any_depth() const;  // any option that changes depth or its valid mask
  void visit(ConfigVisitor& v);
};

struct PerturbedDepth {
  torch::Tensor depth, valid;  // [H,W] metres (0 where invalid), float 0/1
};

// The depth options applied to a depth map (a copy). Used on the source depth (dataset and sparse priors
// consume it; prompts are drawn from it) and on an image-only prior's output (see eval/methods). image [3,H,W] and
// K [3,3]: the view's, needed by sensor.dark and sensor.grazing_deg.
PerturbedDepth perturb_depth(const torch::Tensor& depth, const torch::Tensor& valid, const PerturbOptions& options,
                             uint64_t seed, const torch::Tensor& image = {}, const torch::Tensor& K = {});

// The depth options that make sense for sparse prompts [P,3] (u, v, z) given directly (COLMAP points3D):
// scale, multiplicative noise (depth_noise), holes (that share of prompts dropped) and side (by u or v in an
// image of `width` x `height`). Blur, edge noise and the sensor model need a dense map and leave prompts unchanged.
torch::Tensor perturb_prompts(const torch::Tensor& prompts, const PerturbOptions& options, uint64_t seed, int64_t width,
                              int64_t height);

// Applies the options to the source view's image, depth and valid mask (a copy; the input is unchanged).
ViewTensors perturb_source(const ViewTensors& source, const PerturbOptions& options, uint64_t seed);

// Depth edges: valid pixels whose depth differs from a 4-neighbour's by more than `relative` of itself.
torch::Tensor depth_edges(const torch::Tensor& depth, const torch::Tensor& valid, double relative = 0.05);

}  // namespace isplat
