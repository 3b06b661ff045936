// Batched projection helpers on tensors.
#include "geometry/camera_torch.h"

#include <torch/torch.h>

#include "core/error.h"

namespace isplat {
namespace F = torch::nn::functional;

Camera Camera::select(int64_t b) const {
  ISPLAT_CHECK(batch() > 0, "Camera::select on an unbatched camera");
  return {K[b], T_cw[b], width, height};
}

Camera Camera::to(torch::Dtype dtype) const {
  return {K.to(dtype), T_cw.to(dtype), width, height};
}

Camera to_camera(const View& view, torch::Dtype dtype) {
  auto K = torch::empty({3, 3}, torch::kFloat64);
  auto T = torch::empty({4, 4}, torch::kFloat64);
  const Eigen::Matrix3d Km = view.intr.K();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) K[r][c] = Km(r, c);
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) T[r][c] = view.T_cw(r, c);
  return {K.to(dtype), T.to(dtype), view.intr.width, view.intr.height};
}

Camera stack_cameras(const std::vector<Camera>& cameras) {
  ISPLAT_CHECK(!cameras.empty(), "stack_cameras: no cameras");
  std::vector<torch::Tensor> Ks, Ts;
  for (const auto& c : cameras) {
    ISPLAT_CHECK(c.width == cameras[0].width && c.height == cameras[0].height,
                 "stack_cameras: all cameras must share one image size");
    Ks.push_back(c.K);
    Ts.push_back(c.T_cw);
  }
  return {torch::stack(Ks), torch::stack(Ts), cameras[0].width, cameras[0].height};
}

View to_view(const Camera& camera) {
  ISPLAT_CHECK(camera.batch() == 0, "to_view needs an unbatched camera");
  auto K = camera.K.to(torch::kFloat64).contiguous();
  auto T = camera.T_cw.to(torch::kFloat64).contiguous();
  Eigen::Matrix3d Km;
  View v;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) Km(r, c) = K[r][c].item<double>();
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) v.T_cw(r, c) = T[r][c].item<double>();
  v.intr = Intrinsics::from_K(Km, static_cast<int>(camera.width), static_cast<int>(camera.height));
  return v;
}

torch::Tensor make_K(double fx, double fy, double cx, double cy, torch::Dtype dtype) {
  return torch::tensor({fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0}, torch::kFloat64).reshape({3, 3}).to(dtype);
}

torch::Tensor project_points(const torch::Tensor& points, const torch::Tensor& K) {
  auto p = torch::matmul(points, K.transpose(-1, -2));  // [..., N, 3]
  return p.narrow(-1, 0, 2) / p.narrow(-1, 2, 1);
}

torch::Tensor backproject_points(const torch::Tensor& uv, const torch::Tensor& z, const torch::Tensor& K) {
  auto ones = torch::ones_like(uv.narrow(-1, 0, 1));
  auto h = torch::cat({uv, ones}, -1);                                // [..., N, 3]
  auto rays = torch::matmul(h, torch::inverse(K).transpose(-1, -2));  // z = 1 rays
  return rays * z.unsqueeze(-1);
}

torch::Tensor transform_points(const torch::Tensor& T, const torch::Tensor& points) {
  auto R = T.narrow(-2, 0, 3).narrow(-1, 0, 3);
  auto t = T.narrow(-2, 0, 3).narrow(-1, 3, 1).transpose(-1, -2);  // [..., 1, 3]
  return torch::matmul(points, R.transpose(-1, -2)) + t;
}

torch::Tensor invert_poses(const torch::Tensor& T) {
  auto R = T.narrow(-2, 0, 3).narrow(-1, 0, 3);
  auto t = T.narrow(-2, 0, 3).narrow(-1, 3, 1);
  auto Rt = R.transpose(-1, -2);
  auto out = torch::zeros_like(T);
  out.narrow(-2, 0, 3).narrow(-1, 0, 3).copy_(Rt);
  out.narrow(-2, 0, 3).narrow(-1, 3, 1).copy_(-torch::matmul(Rt, t));
  out.select(-2, 3).select(-1, 3).fill_(1.0);
  return out;
}

torch::Tensor pixel_centers(int64_t height, int64_t width, torch::Dtype dtype) {
  auto opts = torch::TensorOptions().dtype(dtype);
  auto v = torch::arange(height, opts) + 0.5;
  auto u = torch::arange(width, opts) + 0.5;
  auto grids = torch::meshgrid({v, u}, "ij");
  return torch::stack({grids[1], grids[0]}, -1);
}

torch::Tensor usable_depth(const torch::Tensor& depth, const torch::Tensor& valid) {
  return (valid != 0) & torch::isfinite(depth) & (depth > 0);
}

torch::Tensor backproject_depth(const torch::Tensor& depth, const torch::Tensor& K) {
  ISPLAT_CHECK(depth.dim() == 2, "backproject_depth: depth must be [H, W], got ", depth.sizes());
  auto uv = pixel_centers(depth.size(0), depth.size(1), depth.scalar_type()).reshape({-1, 2});
  return backproject_points(uv, depth.reshape({-1}), K.to(depth.scalar_type()))
      .reshape({depth.size(0), depth.size(1), 3});
}

torch::Tensor resize_bilinear(const torch::Tensor& x, int64_t height, int64_t width) {
  return F::interpolate(x, F::InterpolateFuncOptions()
                               .size(std::vector<int64_t>{height, width})
                               .mode(torch::kBilinear)
                               .align_corners(false));
}

std::pair<torch::Tensor, torch::Tensor> resize_with_K(const torch::Tensor& image, const torch::Tensor& K,
                                                      int64_t new_height, int64_t new_width) {
  ISPLAT_CHECK(image.dim() == 3, "resize_with_K: image must be [C, H, W], got ", image.sizes());
  ISPLAT_CHECK(new_height > 0 && new_width > 0, "resize_with_K: target size must be positive");
  const double sy = static_cast<double>(new_height) / image.size(1),
               sx = static_cast<double>(new_width) / image.size(2);
  const bool shrink = sx < 1.0 || sy < 1.0;
  auto out = F::interpolate(image.unsqueeze(0), F::InterpolateFuncOptions()
                                                    .size(std::vector<int64_t>{new_height, new_width})
                                                    .mode(torch::kBilinear)
                                                    .align_corners(false)
                                                    .antialias(shrink))
                 .squeeze(0);
  auto S = torch::diag(torch::tensor({sx, sy, 1.0}, K.options()));
  return {out, torch::matmul(S, K)};
}

torch::Tensor mirror_K(const torch::Tensor& K, int64_t width) {
  ISPLAT_CHECK(K.dim() >= 2 && K.size(-1) == 3 && K.size(-2) == 3, "mirror_K: K must be [..., 3, 3], got ", K.sizes());
  ISPLAT_CHECK(width > 0, "mirror_K: width must be positive, got ", width);
  auto out = K.clone();
  out.select(-2, 0).select(-1, 2).copy_(static_cast<double>(width) - K.select(-2, 0).select(-1, 2));
  out.select(-2, 0).select(-1, 1).neg_();
  return out;
}

std::pair<torch::Tensor, torch::Tensor> crop_with_K(const torch::Tensor& image, const torch::Tensor& K, int64_t x0,
                                                    int64_t y0, int64_t crop_width, int64_t crop_height) {
  ISPLAT_CHECK(image.dim() == 3, "crop_with_K: image must be [C, H, W], got ", image.sizes());
  ISPLAT_CHECK(x0 >= 0 && y0 >= 0 && crop_width > 0 && crop_height > 0 && x0 + crop_width <= image.size(2) &&
                   y0 + crop_height <= image.size(1),
               "crop_with_K: window (", x0, ", ", y0, ", ", crop_width, "x", crop_height, ") is outside the ",
               image.size(2), "x", image.size(1), " image");
  auto out = image.narrow(1, y0, crop_height).narrow(2, x0, crop_width).contiguous();
  auto K2 = K.clone();
  K2[0][2] -= static_cast<double>(x0);
  K2[1][2] -= static_cast<double>(y0);
  return {out, K2};
}

}  // namespace isplat
