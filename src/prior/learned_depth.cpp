// Learned depth: a U-Net or a decoder on frozen SqueezeNet taps, predicting log depth; instance norm
// keeps it stable at batch size 1.
#include "prior/learned_depth.h"

#include <torch/torch.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/weights.h"
#include "geometry/camera_torch.h"
#include "nets/cnn.h"
#include "nets/feature_net.h"
#include "nets/imagenet.h"

namespace isplat {
namespace nn = torch::nn;

namespace {
// SqueezeNet-1.1 `features` taps at strides 2, 4, 8 and 16, and their channels.
const std::vector<int> kSqueezeTaps = {1, 4, 7, 12};
const int64_t kSqueezeChannels[4] = {64, 128, 256, 512};
}  // namespace

LearnedDepthNetImpl::LearnedDepthNetImpl(const LearnedDepthOptions& o) : options(o) {
  const int64_t w = o.width;
  ISPLAT_CHECK(w >= 4, "learned depth net: width ", w, " < 4 (prior.learned_width)");
  if (o.arch == "unet") {
    stem = register_module("stem", nn::Conv2d(nn::Conv2dOptions(3, w, 3).padding(1)));
    down = register_module("down", nn::ModuleList());
    up = register_module("up", nn::ModuleList());
    const int64_t c[5] = {w, 2 * w, 3 * w, 4 * w, 4 * w};
    for (int s = 0; s < 4; ++s) down->push_back(nn::Conv2d(nn::Conv2dOptions(c[s], c[s + 1], 3).stride(2).padding(1)));
    for (int s = 3; s >= 0; --s) up->push_back(nn::Conv2d(nn::Conv2dOptions(c[s + 1] + c[s], c[s], 3).padding(1)));
  } else if (o.arch == "squeeze") {
    const std::string path = find_weights_file(o.backbone);
    ISPLAT_CHECK(!path.empty(), "learned depth net: arch squeeze needs prior.learned_backbone '", o.backbone,
                 "': not found; ", missing_weights_hint());
    backbone = std::make_shared<const FeatureNet>("squeezenet1_1", kSqueezeTaps, path);
    // Coarse to fine: 1x1 laterals bring each tap to the decoder width, 3x3 convs fuse after upsampling.
    lateral = register_module("lateral", nn::ModuleList());
    up = register_module("up", nn::ModuleList());
    for (int t = 0; t < 4; ++t) lateral->push_back(nn::Conv2d(nn::Conv2dOptions(kSqueezeChannels[t], 2 * w, 1)));
    for (int t = 0; t < 3; ++t) up->push_back(nn::Conv2d(nn::Conv2dOptions(4 * w, 2 * w, 3).padding(1)));
    stem = register_module("stem", nn::Conv2d(nn::Conv2dOptions(2 * w + 3, w, 3).padding(1)));  // full resolution
  } else {
    fail("learned depth net: unknown arch '", o.arch, "' (unet | squeeze; config key prior.learned_arch)");
  }
  head = register_module("head", nn::Conv2d(nn::Conv2dOptions(w, 1, 3).padding(1)));
  torch::NoGradGuard g;
  head->weight.mul_(0.1);
  head->bias.fill_(std::log(3.0));  // start at room scale: 3 m everywhere
}

torch::Tensor LearnedDepthNetImpl::forward_log(const torch::Tensor& image, const torch::Tensor& K) {
  torch::Tensor x;
  if (options.arch == "unet") {
    std::vector<torch::Tensor> skips;
    x = torch::relu(instance_norm(stem->forward(2.0 * image - 1.0)));
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
  } else {
    std::vector<torch::Tensor> taps;
    {
      torch::NoGradGuard frozen;  // the pretrained encoder is never trained
      taps = backbone->forward(imagenet_normalize(image));
    }
    x = torch::relu(instance_norm((*lateral)[3]->as<nn::Conv2d>()->forward(taps[3])));
    for (int t = 2; t >= 0; --t) {
      const auto skip = torch::relu(instance_norm((*lateral)[t]->as<nn::Conv2d>()->forward(taps[t])));
      x = resize_bilinear(x, skip.size(2), skip.size(3));
      x = torch::relu(instance_norm((*up)[2 - t]->as<nn::Conv2d>()->forward(torch::cat({x, skip}, 1))));
    }
    x = resize_bilinear(x, image.size(2), image.size(3));
    x = torch::relu(instance_norm(stem->forward(torch::cat({x, 2.0 * image - 1.0}, 1))));
  }
  auto log_depth = head->forward(x);
  if (options.focal_normalized) {
    ISPLAT_CHECK(K.defined() && K.dim() == 3 && K.size(0) == image.size(0),
                 "learned depth net: focal-normalized prediction needs K [B,3,3], got ",
                 K.defined() ? K.sizes() : torch::IntArrayRef{});
    const auto fx_over_w = K.select(1, 0).select(1, 0).to(log_depth.scalar_type()) / static_cast<double>(image.size(3));
    log_depth = log_depth + torch::log(fx_over_w / kCanonicalFocal).view({-1, 1, 1, 1});
  }
  return log_depth;
}

torch::Tensor LearnedDepthNetImpl::forward(const torch::Tensor& image, const torch::Tensor& K) {
  return torch::exp(forward_log(image, K));
}

}  // namespace isplat
