// torchvision feature stacks as plain layer lists with taps; weights from safetensors.
#include "nets/feature_net.h"

#include <torch/torch.h>

#include "core/error.h"
#include "io/safetensors.h"

namespace isplat {
namespace F = torch::nn::functional;

FeatureNet::FeatureNet(const std::string& arch, std::vector<int> taps, const std::string& path)
    : arch_(arch), taps_(std::move(taps)) {
  auto conv = [&](int64_t in, int64_t out, int64_t k, int64_t s, int64_t p) {
    layers_.push_back({Layer::Conv, in, out, k, s, p});
  };
  auto relu = [&] { layers_.push_back({Layer::Relu}); };
  auto pool = [&](int64_t k, int64_t s, bool ceil) {
    Layer l{Layer::MaxPool};
    l.kernel = k;
    l.stride = s;
    l.ceil = ceil;
    layers_.push_back(l);
  };
  auto fire = [&](int64_t in, int64_t sq, int64_t e1, int64_t e3) {
    Layer l{Layer::Fire};
    l.in = in;
    l.squeeze = sq;
    l.e1 = e1;
    l.e3 = e3;
    layers_.push_back(l);
  };
  auto vgg = [&](const std::vector<int64_t>& cfg) {  // conv widths, 0 = max-pool
    int64_t in = 3;
    for (int64_t c : cfg) {
      if (c == 0) {
        pool(2, 2, false);
      } else {
        conv(in, c, 3, 1, 1), relu();
        in = c;
      }
    }
  };
  if (arch == "squeezenet1_1") {
    conv(3, 64, 3, 2, 0), relu(), pool(3, 2, true), fire(64, 16, 64, 64), fire(128, 16, 64, 64), pool(3, 2, true),
        fire(128, 32, 128, 128), fire(256, 32, 128, 128), pool(3, 2, true), fire(256, 48, 192, 192),
        fire(384, 48, 192, 192), fire(384, 64, 256, 256), fire(512, 64, 256, 256);
  } else if (arch == "alexnet") {
    conv(3, 64, 11, 4, 2), relu(), pool(3, 2, false), conv(64, 192, 5, 1, 2), relu(), pool(3, 2, false),
        conv(192, 384, 3, 1, 1), relu(), conv(384, 256, 3, 1, 1), relu(), conv(256, 256, 3, 1, 1), relu(),
        pool(3, 2, false);
  } else if (arch == "vgg16") {
    vgg({64, 64, 0, 128, 128, 0, 256, 256, 256, 0, 512, 512, 512, 0, 512, 512, 512, 0});
  } else if (arch == "vgg19") {
    vgg({64, 64, 0, 128, 128, 0, 256, 256, 256, 256, 0, 512, 512, 512, 512, 0, 512, 512, 512, 512, 0});
  } else {
    fail("feature network: unknown architecture '", arch, "' (squeezenet1_1 | vgg16 | vgg19 | alexnet)");
  }
  for (int t : taps_) ISPLAT_CHECK(t >= 0 && t < static_cast<int>(layers_.size()), arch, ": tap ", t, " out of range");
  // Parameters, in torchvision's names: random only when no file is given, else the shapes the file
  // must provide.
  const bool random = path.empty();
  std::map<std::string, std::vector<int64_t>> expected;
  auto add = [&](const std::string& name, int64_t out, int64_t in, int64_t k) {
    if (!random) {
      expected[name + ".weight"] = {out, in, k, k};
      expected[name + ".bias"] = {out};
      return;
    }
    const double bound = 1.0 / std::sqrt(static_cast<double>(in * k * k));
    params_[name + ".weight"] = (torch::rand({out, in, k, k}) * 2 - 1) * bound;
    params_[name + ".bias"] = (torch::rand({out}) * 2 - 1) * bound;
  };
  for (size_t i = 0; i < layers_.size(); ++i) {
    const Layer& l = layers_[i];
    const std::string n = std::to_string(i);
    if (l.kind == Layer::Conv) add(n, l.out, l.in, l.kernel);
    if (l.kind == Layer::Fire) {
      add(n + ".squeeze", l.squeeze, l.in, 1);
      add(n + ".expand1x1", l.e1, l.squeeze, 1);
      add(n + ".expand3x3", l.e3, l.squeeze, 3);
    }
  }
  if (random) return;
  const SafeTensors st = read_safetensors(path);
  std::vector<std::string> missing;
  for (const auto& [name, shape] : expected) {
    const std::string alt = "features." + name;
    const std::string key = st.has(name) ? name : st.has(alt) ? alt : "";
    if (key.empty()) {
      missing.push_back(name);
      continue;
    }
    const auto& w = st.at(key);
    if (w.sizes() != torch::IntArrayRef(shape))
      fail(path, ": tensor '", key, "' has shape ", w.sizes(), ", ", arch, " expects ", torch::IntArrayRef(shape));
    params_[name] = w.to(torch::kFloat32).contiguous();
  }
  if (!missing.empty())
    fail(path, ": not a torchvision ", arch, " `features` checkpoint; missing ", missing.size(), " tensors, e.g. '",
         missing.front(), "'");
  pretrained_ = true;
}

std::vector<torch::Tensor> FeatureNet::forward(const torch::Tensor& input) const {
  std::vector<torch::Tensor> out;
  auto x = input;
  const int last = taps_.empty() ? -1 : *std::max_element(taps_.begin(), taps_.end());
  auto conv = [&](const torch::Tensor& t, const std::string& n, int64_t stride, int64_t pad) {
    return F::conv2d(t, params_.at(n + ".weight"),
                     F::Conv2dFuncOptions().bias(params_.at(n + ".bias")).stride(stride).padding(pad));
  };
  for (int i = 0; i <= last; ++i) {
    const Layer& l = layers_[i];
    const std::string n = std::to_string(i);
    switch (l.kind) {
      case Layer::Conv:
        x = conv(x, n, l.stride, l.pad);
        break;
      case Layer::Relu:
        x = torch::relu(x);
        break;
      case Layer::MaxPool:
        x = F::max_pool2d(x, F::MaxPool2dFuncOptions(l.kernel).stride(l.stride).ceil_mode(l.ceil));
        break;
      case Layer::Fire: {
        auto s = torch::relu(conv(x, n + ".squeeze", 1, 0));
        x = torch::cat({torch::relu(conv(s, n + ".expand1x1", 1, 0)), torch::relu(conv(s, n + ".expand3x3", 1, 1))}, 1);
        break;
      }
    }
    if (std::find(taps_.begin(), taps_.end(), i) != taps_.end()) out.push_back(x);
  }
  return out;
}

std::vector<int64_t> FeatureNet::tap_channels() const {
  std::vector<int64_t> c;
  int64_t cur = 3;
  for (size_t i = 0; i < layers_.size(); ++i) {
    if (layers_[i].kind == Layer::Conv) cur = layers_[i].out;
    if (layers_[i].kind == Layer::Fire) cur = layers_[i].e1 + layers_[i].e3;
    if (std::find(taps_.begin(), taps_.end(), static_cast<int>(i)) != taps_.end()) c.push_back(cur);
  }
  return c;
}

std::vector<int> FeatureNet::lpips_taps(const std::string& arch) {
  if (arch == "squeezenet1_1") return {1, 4, 7, 9, 10, 11, 12};
  if (arch == "alexnet") return {1, 4, 7, 9, 11};
  if (arch == "vgg16") return {3, 8, 15, 22, 29};
  fail("LPIPS: no v0.1 definition for '", arch, "' (squeeze | alex | vgg)");
}

std::vector<int> FeatureNet::perceptual_taps(const std::string& arch) {
  if (arch == "vgg16") return {3, 8, 15, 22};  // relu1_2, relu2_2, relu3_3, relu4_3
  if (arch == "vgg19") return {3, 8, 17, 26};  // relu1_2, relu2_2, relu3_4, relu4_4
  if (arch == "squeezenet1_1") return {1, 4, 7, 9, 12};
  if (arch == "alexnet") return {1, 4, 7, 9, 11};
  fail("perceptual loss: unknown network '", arch, "'");
}

torch::Tensor normalize_channels(const torch::Tensor& f) {
  return f / (torch::sqrt((f * f).sum(1, true)) + 1e-10);
}

}  // namespace isplat
