// A depth sensor's errors on true depth (perturb.sensor): missing returns beyond its range, at grazing angles, on dark
// surfaces and in the shadow behind occluders, flying pixels between surfaces, noise growing with depth squared,
// disparity quantization and a misregistration to the colour image. Each is off by default; preset kinect turns on a
// structured-light camera's combination. Deterministic for a seed.
#pragma once
#include <cstdint>
#include <string>

#include <torch/types.h>

namespace isplat {

class ConfigVisitor;

struct SensorOptions {
  std::string preset = "none";       // none | kinect (then every value below stays at its default)
  double max_range = 0.0;            // metres: no return beyond (0 = off)
  double grazing_deg = 0.0;          // no return where the ray meets the surface's normal at more than this (0 = off)
  double dark = 0.0;                 // no return where the colour image's linear luminance is below this (0 = off)
  int64_t shadow_px = 0;             // no return within this many px behind a nearer surface at a depth edge (0 = off)
  double flying = 0.0;               // share of depth-edge pixels given a depth between their neighbours' surfaces
  double noise_z2 = 0.0;             // depth noise sigma = noise_z2 * z^2 (metres; noise_z2 in 1/m)
  double disparity_step = 0.0;       // 1/z snapped to multiples of this (1/m): steps of about step * z^2 (0 = off)
  int64_t shift_x = 0, shift_y = 0;  // misregistration: depth moved this many px right / down against the colour
  bool any() const;                  // any effect on (a preset included)
  // The values in effect: the preset's, or these. Error when a preset is given together with values.
  SensorOptions resolved() const;
  void visit(ConfigVisitor& v);
};

struct SensorDepth {
  torch::Tensor depth, valid;  // [H,W] metres (0 where invalid), float 0/1
};

// The sensor's view of true depth [H,W] (valid [H,W]). image [3,H,W] sRGB (needed by dark), K [3,3] (needed by
// grazing_deg); either may be undefined when the options do not need it (Error naming the option otherwise).
SensorDepth apply_sensor(const torch::Tensor& depth, const torch::Tensor& valid, const SensorOptions& options,
                         uint64_t seed, const torch::Tensor& image = {}, const torch::Tensor& K = {});

// The angle (degrees) between each pixel's ray and the surface normal estimated from the depth map (central
// differences where the surface runs on steadily, one-sided beside invalid pixels or depth edges); NaN where no normal
// can be estimated. [H,W]
torch::Tensor incidence_deg(const torch::Tensor& depth, const torch::Tensor& valid, const torch::Tensor& K);

// Valid pixels within `radius` px (Chebyshev) of a depth edge that have a 5% nearer valid pixel within radius + 1:
// the far side of each occlusion edge. [H,W] bool.
torch::Tensor far_edge_band(const torch::Tensor& depth, const torch::Tensor& valid, int64_t radius);

}  // namespace isplat
