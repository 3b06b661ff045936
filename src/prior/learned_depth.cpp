// Small U-Net predicting log-depth; instance norm keeps it stable at batch size 1.
#include "prior/learned_depth.h"

#include <torch/torch.h>

#include <cmath>

#include "geometry/camera_torch.h"
#include "nets/cnn.h"

namespace isplat {
namespace nn = torch::nn;

LearnedDepthNetImpl::LearnedDepthNetImpl(int64_t w) {
  stem = register_module("stem", nn::Conv2d(nn::Conv2dOptions(3, w, 3).padding(1)));
  down = register_module("down", nn::ModuleList());
  up = register_module("up", nn::ModuleList());
  const int64_t c[5] = {w, 2 * w, 3 * w, 4 * w, 4 * w};
  for (int s = 0; s < 4; ++s) down->push_back(nn::Conv2d(nn::Conv2dOptions(c[s], c[s + 1], 3).stride(2).padding(1)));
  for (int s = 3; s >= 0; --s) up->push_back(nn::Conv2d(nn::Conv2dOptions(c[s + 1] + c[s], c[s], 3).padding(1)));
  head = register_module("head", nn::Conv2d(nn::Conv2dOptions(w, 1, 3).padding(1)));
  torch::NoGradGuard g;
  head->weight.mul_(0.1);
  head->bias.fill_(std::log(3.0));  // start at room scale: 3 m everywhere
}

torch::Tensor LearnedDepthNetImpl::forward_log(const torch::Tensor& image) {
  std::vector<torch::Tensor> skips;
  auto x = torch::relu(instance_norm(stem->forward(2.0 * image - 1.0)));
  for (auto& m : *down) {
    skips.push_back(x);
    x = torch::relu(instance_norm(m->as<nn::Conv2d>()->forward(x)));
  }
  for (auto& m : *up) {
    auto skip = skips.back();
    skips.pop_back();
    x = resize_bilinear(x, skip.size(2), skip.size(3));
    x = torch::relu(instance_norm(m->as<nn::Conv2d>()->forward(torch::cat({x, skip}, 1))));
  }
  return head->forward(x);
}

torch::Tensor LearnedDepthNetImpl::forward(const torch::Tensor& image) {
  return torch::exp(forward_log(image));
}

}  // namespace isplat
