// Batched pinhole projection and poses on torch tensors, for the model and renderer.
#pragma once
#include <torch/types.h>

#include "geometry/camera.h"

namespace isplat {

// One camera or a batch: K [3,3] | [B,3,3], T_cw [4,4] | [B,4,4] (float32 or float64).
struct Camera {
  torch::Tensor K;
  torch::Tensor T_cw;
  int64_t width = 0, height = 0;

  int64_t batch() const { return K.dim() == 3 ? K.size(0) : 0; }  // 0 = unbatched
  Camera select(int64_t b) const;                                 // one camera from a batch
  Camera to(torch::Dtype dtype) const;
};

Camera to_camera(const View& view, torch::Dtype dtype = torch::kFloat32);
Camera stack_cameras(const std::vector<Camera>& cameras);  // same size required
View to_view(const Camera& camera);                        // unbatched only

torch::Tensor make_K(double fx, double fy, double cx, double cy, torch::Dtype dtype = torch::kFloat32);

// points [..., N, 3] (camera space), K [..., 3, 3] -> continuous pixel coordinates [..., N, 2].
torch::Tensor project_points(const torch::Tensor& points, const torch::Tensor& K);
// uv [..., N, 2] with planar depth z [..., N] -> camera-space points [..., N, 3].
torch::Tensor backproject_points(const torch::Tensor& uv, const torch::Tensor& z, const torch::Tensor& K);
// T [..., 4, 4] applied to points [..., N, 3].
torch::Tensor transform_points(const torch::Tensor& T, const torch::Tensor& points);
torch::Tensor invert_poses(const torch::Tensor& T);  // rigid inverse of [..., 4, 4]
// Pixel-centre coordinates (j + 0.5, i + 0.5) as [H, W, 2] (u, v).
torch::Tensor pixel_centers(int64_t height, int64_t width, torch::Dtype dtype = torch::kFloat32);
// Where depth can be used: the mask says so and the depth is finite and positive (bool [H, W]).
torch::Tensor usable_depth(const torch::Tensor& depth, const torch::Tensor& valid);
// Back-project a depth map [H, W] through K [3, 3] at pixel centres: [H, W, 3].
torch::Tensor backproject_depth(const torch::Tensor& depth, const torch::Tensor& K);

// Maps [B, C, h, w] resized bilinearly to height x width (align_corners = false, no antialiasing).
torch::Tensor resize_bilinear(const torch::Tensor& x, int64_t height, int64_t width);
// Image [C, H, W] resized with its intrinsics K [3, 3] (bilinear with antialiasing when shrinking).
std::pair<torch::Tensor, torch::Tensor> resize_with_K(const torch::Tensor& image, const torch::Tensor& K,
                                                      int64_t new_height, int64_t new_width);
// Intrinsics [..., 3, 3] of the left-right mirrored image of this width: cx -> W - cx (pixel centres at j + 0.5),
// skew negated; fx, fy and cy are unchanged.
torch::Tensor mirror_K(const torch::Tensor& K, int64_t width);
// Crop [C, H, W] at top-left (x0, y0) with its intrinsics.
std::pair<torch::Tensor, torch::Tensor> crop_with_K(const torch::Tensor& image, const torch::Tensor& K, int64_t x0,
                                                    int64_t y0, int64_t crop_width, int64_t crop_height);

}  // namespace isplat
