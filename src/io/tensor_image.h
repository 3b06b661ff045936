// Conversions between OpenCV images (data code) and torch tensors (model code).
#pragma once
#include <torch/types.h>
#include <opencv2/core.hpp>

namespace isplat {

torch::Tensor image_to_tensor(const cv::Mat& rgb);  // CV_32FC3 [H,W,3] -> float [3,H,W]
cv::Mat tensor_to_image(const torch::Tensor& chw);  // float [3,H,W] (or [1,H,W]) -> CV_32FC3/CV_32FC1
torch::Tensor map_to_tensor(const cv::Mat& map);    // CV_32FC1 / CV_8UC1 [H,W] -> float [H,W]
cv::Mat tensor_to_map(const torch::Tensor& hw);     // float [H,W] -> CV_32FC1

}  // namespace isplat
