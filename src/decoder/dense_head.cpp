// The dense head: fuse at a quarter resolution, refine while upsampling, 14 channels per pixel.
#include "decoder/dense_head.h"

#include <torch/torch.h>

#include <vector>

#include "decoder/composer.h"
#include "geometry/camera_torch.h"

namespace isplat {
namespace nn = torch::nn;

DenseHeadImpl::DenseHeadImpl(int64_t dd, int64_t cd, int64_t width) : dino_dim(dd), cnn_dim(cd) {
  reduce = register_module("reduce", nn::Conv2d(nn::Conv2dOptions(dd + cd, width, 3).padding(1)));
  refine1 = register_module("refine1", nn::Conv2d(nn::Conv2dOptions(width, width, 3).padding(1)));
  refine2 = register_module("refine2", nn::Conv2d(nn::Conv2dOptions(width, width / 2, 3).padding(1)));
  out = register_module("out", nn::Conv2d(nn::Conv2dOptions(width / 2, kDeltaDim, 1)));
  torch::NoGradGuard g;
  out->weight.zero_();
  out->bias.zero_();
}

torch::Tensor DenseHeadImpl::forward(const EncoderFeatures& f, int64_t width, int64_t height) {
  auto up = [](const torch::Tensor& x, int64_t h, int64_t w) { return resize_bilinear(x, h, w); };
  const int64_t h4 = (height + 3) / 4, w4 = (width + 3) / 4;
  std::vector<torch::Tensor> parts;
  if (dino_dim > 0) parts.push_back(up(f.dino.narrow(0, 0, 1), h4, w4));
  if (cnn_dim > 0) parts.push_back(up(f.cnn.narrow(0, 0, 1), h4, w4));
  auto x = torch::relu(reduce->forward(torch::cat(parts, 1)));
  x = torch::relu(refine1->forward(up(x, (height + 1) / 2, (width + 1) / 2)));
  x = torch::relu(refine2->forward(up(x, height, width)));
  return out->forward(x);
}

}  // namespace isplat
