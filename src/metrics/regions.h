// Where an image's error lives: a scored mask split into image regions, the render's detail against the
// target's, and how densely Gaussians cover each region (the evaluator's scoring.regions).
#pragma once
#include <string>
#include <utility>
#include <vector>

#include <torch/types.h>

#include "geometry/camera_torch.h"

namespace isplat {

// Named masks [H,W] (float, 0 or 1), each a part of `mask`: `near` and `far` (the reference depth at or below and
// above its median over the mask's valid pixels), `textured` and `flat` (the target's local gradient energy, a 5x5
// mean of the squared central differences of its grey level, above and at or below its median over the mask),
// `silhouette` (within `edge_px` pixels of a reference depth edge: neighbours whose depths differ by edge_jump of
// the nearer or more, or a valid pixel beside an invalid one) and `interior` (valid, beyond that band).
// target [3,H,W]; ref_depth [H,W] valid where > 0 and finite, or undefined: then only textured and flat.
std::vector<std::pair<std::string, torch::Tensor>> image_regions(const torch::Tensor& target,
                                                                 const torch::Tensor& ref_depth,
                                                                 const torch::Tensor& mask, int64_t edge_px = 2,
                                                                 double edge_jump = 0.05);

// The render's detail against the target's: the energy of a 3x3 Laplacian of the grey level over the mask's pixels
// (those with a whole 3x3 neighbourhood in the image), rendered over target. 1 = as much fine structure as the target,
// below 1 = blurrier, above = noisier. NaN when the mask is empty or the target has no detail there.
double detail_ratio(const torch::Tensor& rendered, const torch::Tensor& target, const torch::Tensor& mask);

// Gaussian centres (means [N,3], world frame) in front of `camera` whose projection falls on the mask's pixels, per
// masked pixel (hidden ones count too: this is how many the representation spends there). NaN when the mask is empty.
double centre_density(const torch::Tensor& means, const Camera& camera, const torch::Tensor& mask);

}  // namespace isplat
