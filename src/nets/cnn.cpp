// CNN feature branch: residual stages and multi-scale fusion at quarter resolution.
#include "nets/cnn.h"

#include <torch/torch.h>

#include "core/config.h"
#include "geometry/camera_torch.h"

namespace isplat {
namespace nn = torch::nn;
namespace F = torch::nn::functional;

void CNNOptions::visit(ConfigVisitor& v) {
  v.field("width", width, "base channel width; the four stages use 1x, 2x, 3x, 4x", Range::between(4, 1024));
  v.field("out_channels", out_channels, "output feature channels (paper/release: 128)", Range::between(1, 4096));
}

torch::Tensor instance_norm(const torch::Tensor& x) {
  return F::instance_norm(x, F::InstanceNormFuncOptions().eps(1e-5));
}

ResidualBlockImpl::ResidualBlockImpl(int64_t in, int64_t out, int64_t stride) {
  conv1 = register_module("conv1", nn::Conv2d(nn::Conv2dOptions(in, out, 3).stride(stride).padding(1)));
  conv2 = register_module("conv2", nn::Conv2d(nn::Conv2dOptions(out, out, 3).padding(1)));
  if (stride != 1 || in != out)
    down = register_module("down", nn::Conv2d(nn::Conv2dOptions(in, out, 1).stride(stride)));
}

torch::Tensor ResidualBlockImpl::forward(const torch::Tensor& x) {
  auto y = torch::relu(instance_norm(conv1->forward(x)));
  y = instance_norm(conv2->forward(y));
  auto skip = down ? instance_norm(down->forward(x)) : x;
  return torch::relu(skip + y);
}

CNNEncoderImpl::CNNEncoderImpl(const CNNOptions& o) : out_channels(o.out_channels) {
  const int64_t w = o.width;
  stem = register_module("stem", nn::Conv2d(nn::Conv2dOptions(3, w, 7).stride(2).padding(3)));
  blocks = register_module("blocks", nn::ModuleList());
  const int64_t widths[4] = {w, 2 * w, 3 * w, 4 * w}, strides[4] = {1, 2, 2, 2};
  int64_t in = w;
  for (int s = 0; s < 4; ++s) {
    blocks->push_back(ResidualBlock(in, widths[s], strides[s]));
    blocks->push_back(ResidualBlock(widths[s], widths[s], 1));
    in = widths[s];
  }
  fuse = register_module("fuse", nn::Conv2d(nn::Conv2dOptions(w + 2 * w + 3 * w + 4 * w, out_channels, 3).padding(1)));
  project = register_module("project", nn::Conv2d(nn::Conv2dOptions(out_channels, out_channels, 1)));
}

torch::Tensor CNNEncoderImpl::forward(const torch::Tensor& image) {
  auto x = torch::relu(instance_norm(stem->forward(2.0 * image - 1.0)));  // H/2
  const int64_t H4 = (image.size(2) + 3) / 4, W4 = (image.size(3) + 3) / 4;
  std::vector<torch::Tensor> scales;
  for (size_t b = 0; b < blocks->size(); ++b) {
    x = blocks[b]->as<ResidualBlock>()->forward(x);
    if (b % 2 == 1)  // end of a stage: H/2, H/4, H/8, H/16 -> all to H/4
      scales.push_back(resize_bilinear(x, H4, W4));
  }
  auto fused = torch::relu(instance_norm(fuse->forward(torch::cat(scales, 1))));
  return project->forward(fused);
}

}  // namespace isplat
