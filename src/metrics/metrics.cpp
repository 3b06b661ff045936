// PSNR, SSIM (separable Gaussian filtering over raw pointers) and LPIPS.
#include "metrics/metrics.h"

#include <ATen/Parallel.h>
#include <torch/torch.h>

#include <cmath>
#include <filesystem>
#include <limits>

#include "core/error.h"
#include "core/weights.h"
#include "io/safetensors.h"

namespace isplat {
namespace F = torch::nn::functional;

namespace {
void check_pair(const torch::Tensor& a, const torch::Tensor& b, const char* what) {
  ISPLAT_CHECK(a.dim() == 3 && a.sizes() == b.sizes(), what, ": images must be [C,H,W] of equal size, got ", a.sizes(),
               " and ", b.sizes());
}
}  // namespace

double psnr(const torch::Tensor& a, const torch::Tensor& b, const torch::Tensor& mask) {
  check_pair(a, b, "psnr");
  auto d2 = (a.to(torch::kFloat64) - b.to(torch::kFloat64)).pow(2).mean(0);  // [H,W]
  double mse;
  if (mask.defined()) {
    auto m = (mask != 0).to(torch::kFloat64);
    const double n = m.sum().item<double>();
    if (n == 0) return std::numeric_limits<double>::quiet_NaN();
    mse = (d2 * m).sum().item<double>() / n;
  } else {
    mse = d2.mean().item<double>();
  }
  return mse <= 0 ? std::numeric_limits<double>::infinity() : -10.0 * std::log10(mse);
}

torch::Tensor ssim_map(const torch::Tensor& a_in, const torch::Tensor& b_in) {
  check_pair(a_in, b_in, "ssim");
  constexpr int R = 5;  // 11x11 window
  constexpr double sigma = 1.5, C1 = 0.01 * 0.01, C2 = 0.03 * 0.03;
  double w[2 * R + 1], wsum = 0;
  for (int k = -R; k <= R; ++k) wsum += w[k + R] = std::exp(-k * k / (2 * sigma * sigma));
  for (double& x : w) x /= wsum;
  auto a = a_in.to(torch::kFloat64).contiguous(), b = b_in.to(torch::kFloat64).contiguous();
  const int64_t C = a.size(0), H = a.size(1), W = a.size(2);
  auto out = torch::full({H, W}, std::numeric_limits<double>::quiet_NaN(), torch::kFloat64);
  if (H < 2 * R + 1 || W < 2 * R + 1) return out;
  const int64_t Ho = H - 2 * R, Wo = W - 2 * R;
  std::vector<double> acc(static_cast<size_t>(Ho * Wo), 0.0);
  // Per channel: horizontal pass over the five moments, then vertical pass, at valid positions only.
  for (int64_t c = 0; c < C; ++c) {
    const double* pa = a.data_ptr<double>() + c * H * W;
    const double* pb = b.data_ptr<double>() + c * H * W;
    std::vector<double> h(static_cast<size_t>(5 * H * Wo));
    at::parallel_for(0, H, 8, [&](int64_t r0, int64_t r1) {
      for (int64_t i = r0; i < r1; ++i)
        for (int64_t j = 0; j < Wo; ++j) {
          double s[5] = {0, 0, 0, 0, 0};
          for (int k = 0; k <= 2 * R; ++k) {
            const double x = pa[i * W + j + k], y = pb[i * W + j + k], wk = w[k];
            s[0] += wk * x, s[1] += wk * y, s[2] += wk * x * x, s[3] += wk * y * y, s[4] += wk * x * y;
          }
          for (int m = 0; m < 5; ++m) h[(m * H + i) * Wo + j] = s[m];
        }
    });
    at::parallel_for(0, Ho, 8, [&](int64_t r0, int64_t r1) {
      for (int64_t i = r0; i < r1; ++i)
        for (int64_t j = 0; j < Wo; ++j) {
          double s[5] = {0, 0, 0, 0, 0};
          for (int k = 0; k <= 2 * R; ++k)
            for (int m = 0; m < 5; ++m) s[m] += w[k] * h[(m * H + i + k) * Wo + j];
          const double mx = s[0], my = s[1], vx = s[2] - mx * mx, vy = s[3] - my * my, cxy = s[4] - mx * my;
          acc[i * Wo + j] += ((2 * mx * my + C1) * (2 * cxy + C2)) / ((mx * mx + my * my + C1) * (vx + vy + C2));
        }
    });
  }
  double* o = out.data_ptr<double>();
  for (int64_t i = 0; i < Ho; ++i)
    for (int64_t j = 0; j < Wo; ++j) o[(i + R) * W + j + R] = acc[i * Wo + j] / C;
  return out;
}

double ssim(const torch::Tensor& a, const torch::Tensor& b, const torch::Tensor& mask) {
  auto map = ssim_map(a, b);
  auto ok = torch::isfinite(map);
  if (mask.defined()) ok = ok & (mask != 0);
  const int64_t n = ok.sum().item<int64_t>();
  if (n == 0) return std::numeric_limits<double>::quiet_NaN();
  return map.masked_select(ok).sum().item<double>() / n;
}

namespace {
// LPIPS network name -> torchvision backbone ("" if unknown); its weights are "<arch>_features.safetensors".
std::string lpips_arch(const std::string& net) {
  return net == "squeeze" ? "squeezenet1_1" : net == "alex" ? "alexnet" : net == "vgg" ? "vgg16" : "";
}
const char* kLpipsNets = "(squeeze | alex | vgg)";
}  // namespace

Lpips::Lpips(const std::string& net, const std::string& backbone, const std::string& heads) : net_(net) {
  const std::string arch = lpips_arch(net);
  ISPLAT_CHECK(!arch.empty(), "LPIPS: unknown network '", net, "' ", kLpipsNets);
  ISPLAT_CHECK(!backbone.empty() && !heads.empty(), "LPIPS-", net, " needs a backbone and linear-head weights file");
  features_ = std::make_unique<FeatureNet>(arch, FeatureNet::lpips_taps(arch), backbone);
  const SafeTensors st = read_safetensors(heads);
  const auto channels = features_->tap_channels();
  for (size_t l = 0; l < channels.size(); ++l) {
    const std::string key = cat("lin", l, ".model.1.weight");
    if (!st.has(key)) fail(heads, ": missing '", key, "' (LPIPS v0.1 ", net, " heads)");
    const auto& w = st.at(key);
    if (w.sizes() != torch::IntArrayRef({1, channels[l], 1, 1}))
      fail(heads, ": '", key, "' has shape ", w.sizes(), ", expected [1, ", channels[l], ", 1, 1]");
    heads_.push_back(w.to(torch::kFloat32));
  }
  if (st.tensors.size() != channels.size())
    fail(heads, ": has ", st.tensors.size(), " tensors, LPIPS-", net, " uses ", channels.size(), " heads");
}

double Lpips::operator()(const torch::Tensor& a, const torch::Tensor& b, const torch::Tensor& mask) const {
  return mean_distance(distance_maps(a, b), mask);
}

std::vector<torch::Tensor> Lpips::distance_maps(const torch::Tensor& a, const torch::Tensor& b) const {
  check_pair(a, b, "LPIPS");
  torch::NoGradGuard g;
  auto shift = torch::tensor({-0.030f, -0.088f, -0.188f}).view({1, 3, 1, 1});
  auto scale = torch::tensor({0.458f, 0.448f, 0.450f}).view({1, 3, 1, 1});
  auto prep = [&](const torch::Tensor& x) { return ((x.unsqueeze(0).to(torch::kFloat32) * 2 - 1) - shift) / scale; };
  const auto fa = features_->forward(prep(a)), fb = features_->forward(prep(b));
  std::vector<torch::Tensor> maps;
  for (size_t l = 0; l < fa.size(); ++l)
    maps.push_back(F::conv2d((normalize_channels(fa[l]) - normalize_channels(fb[l])).pow(2), heads_[l]));
  return maps;
}

double Lpips::mean_distance(const std::vector<torch::Tensor>& maps, const torch::Tensor& mask) {
  torch::NoGradGuard g;
  double total = 0;
  for (const auto& d : maps) {  // [1,1,h,w]
    if (mask.defined()) {
      auto m = F::interpolate(
          mask.to(torch::kFloat32).view({1, 1, mask.size(0), mask.size(1)}),
          F::InterpolateFuncOptions().size(std::vector<int64_t>{d.size(2), d.size(3)}).mode(torch::kArea));
      const double msum = m.sum().item<double>();
      if (msum <= 0) return std::numeric_limits<double>::quiet_NaN();
      total += (d * m).sum().item<double>() / msum;
    } else {
      total += d.mean().item<double>();
    }
  }
  return total;
}

std::unique_ptr<Lpips> Lpips::from_folder(const std::string& net, const std::string& requested, std::string& why) {
  namespace fs = std::filesystem;
  const std::string arch = lpips_arch(net);
  if (arch.empty()) {
    why = cat("LPIPS: unknown network '", net, "' ", kLpipsNets);
    return nullptr;
  }
  const std::string backbone_file = arch + "_features.safetensors",
                    heads_file = "lpips_v0.1_" + net + "_lin.safetensors";
  std::error_code ec;
  const bool lookup = requested.empty() || (requested == "weights" && !fs::is_directory(requested, ec));
  const std::string folder = lookup ? find_weights_folder({backbone_file, heads_file}) : requested;
  const fs::path backbone = fs::path(folder) / backbone_file, heads = fs::path(folder) / heads_file;
  if (folder.empty() || !fs::exists(backbone) || !fs::exists(heads)) {
    why = lookup ? cat("LPIPS-", net, " needs ", backbone_file, " and ", heads_file, "; ", missing_weights_hint())
                 : cat("LPIPS-", net, " needs ", backbone.string(), " and ", heads.string(), " (", kGetWeightsCommand,
                       " gets the published ones)");
    return nullptr;
  }
  return std::make_unique<Lpips>(net, backbone.string(), heads.string());
}

}  // namespace isplat
