// cv::Mat <-> torch::Tensor copies (the tensor always owns its memory).
#include "io/tensor_image.h"

#include <torch/torch.h>

#include "core/error.h"

namespace isplat {

torch::Tensor image_to_tensor(const cv::Mat& rgb) {
  ISPLAT_CHECK(rgb.type() == CV_32FC3, "image_to_tensor expects CV_32FC3, got type ", rgb.type());
  cv::Mat c = rgb.isContinuous() ? rgb : rgb.clone();
  return torch::from_blob(c.data, {c.rows, c.cols, 3}, torch::kFloat32).permute({2, 0, 1}).contiguous();
}

cv::Mat tensor_to_image(const torch::Tensor& chw) {
  ISPLAT_CHECK(chw.dim() == 3 && (chw.size(0) == 3 || chw.size(0) == 1),
               "tensor_to_image expects [3,H,W] or [1,H,W], got ", chw.sizes());
  auto hwc = chw.detach().to(torch::kCPU, torch::kFloat32).permute({1, 2, 0}).contiguous();
  cv::Mat out(static_cast<int>(hwc.size(0)), static_cast<int>(hwc.size(1)), chw.size(0) == 3 ? CV_32FC3 : CV_32FC1);
  std::memcpy(out.data, hwc.data_ptr<float>(), hwc.numel() * sizeof(float));
  return out;
}

torch::Tensor map_to_tensor(const cv::Mat& map) {
  ISPLAT_CHECK(map.channels() == 1, "map_to_tensor expects one channel");
  cv::Mat f;
  map.convertTo(f, CV_32F);
  if (!f.isContinuous()) f = f.clone();
  return torch::from_blob(f.data, {f.rows, f.cols}, torch::kFloat32).clone();
}

cv::Mat tensor_to_map(const torch::Tensor& hw) {
  ISPLAT_CHECK(hw.dim() == 2, "tensor_to_map expects [H,W], got ", hw.sizes());
  auto t = hw.detach().to(torch::kCPU, torch::kFloat32).contiguous();
  cv::Mat out(static_cast<int>(t.size(0)), static_cast<int>(t.size(1)), CV_32FC1);
  std::memcpy(out.data, t.data_ptr<float>(), t.numel() * sizeof(float));
  return out;
}

}  // namespace isplat
