// Forward splatting of source pixels into the target, then a morphological closing.
#include "metrics/mask.h"

#include <torch/torch.h>
#include <opencv2/imgproc.hpp>

#include <cmath>

#include "core/error.h"
#include "io/tensor_image.h"

namespace isplat {

torch::Tensor projected_mask(const torch::Tensor& depth_in, const torch::Tensor& valid_in, const View& source,
                             const View& target, int radius) {
  auto depth = depth_in.to(torch::kFloat32).contiguous();
  auto valid = valid_in.to(torch::kFloat32).contiguous();
  ISPLAT_CHECK(depth.dim() == 2 && depth.size(0) == source.intr.height && depth.size(1) == source.intr.width,
               "projected_mask: depth ", depth.sizes(), " does not match the source camera ", source.intr.width, "x",
               source.intr.height);
  const int H = source.intr.height, W = source.intr.width, Ht = target.intr.height, Wt = target.intr.width;
  cv::Mat mask = cv::Mat::zeros(Ht, Wt, CV_8UC1);
  const Pose rel = target.T_cw * invert_pose(source.T_cw);
  const float* d = depth.data_ptr<float>();
  const float* v = valid.data_ptr<float>();
  const double scale_f = std::sqrt(target.intr.fx * target.intr.fy / (source.intr.fx * source.intr.fy));
  for (int i = 0; i < H; ++i)
    for (int j = 0; j < W; ++j) {
      const int64_t k = static_cast<int64_t>(i) * W + j;
      if (v[k] == 0.0f || !(d[k] > 0.0f)) continue;
      const Eigen::Vector3d Xt = transform_point(rel, source.intr.backproject(j + 0.5, i + 0.5, d[k]));
      if (Xt.z() <= 1e-6) continue;
      const Eigen::Vector2d uv = target.intr.project(Xt);
      // Footprint of one source pixel in the target, so zoom-in pairs leave no holes.
      const double half = 0.5 * std::max(1.0, scale_f * d[k] / Xt.z());
      const int x0 = static_cast<int>(std::floor(uv.x() - half)), x1 = static_cast<int>(std::floor(uv.x() + half));
      const int y0 = static_cast<int>(std::floor(uv.y() - half)), y1 = static_cast<int>(std::floor(uv.y() + half));
      if (x1 < 0 || y1 < 0 || x0 >= Wt || y0 >= Ht) continue;
      for (int y = std::max(0, y0); y <= std::min(Ht - 1, y1); ++y)
        for (int x = std::max(0, x0); x <= std::min(Wt - 1, x1); ++x) mask.at<uint8_t>(y, x) = 1;
    }
  if (radius > 0) {
    const cv::Mat kernel = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * radius + 1, 2 * radius + 1));
    cv::morphologyEx(mask, mask, cv::MORPH_CLOSE, kernel);  // default border: never erodes from the image edge
  }
  return map_to_tensor(mask);
}

}  // namespace isplat
