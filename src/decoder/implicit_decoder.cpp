// Feature query, gated fusion and the update MLP; the decoder options.
#include "decoder/implicit_decoder.h"

#include <torch/torch.h>

#include <algorithm>
#include <functional>

#include "core/config.h"
#include "core/error.h"
#include "core/precision.h"
#include "decoder/composer.h"
#include "decoder/feature_sampler.h"

namespace isplat {
namespace nn = torch::nn;
namespace F = torch::nn::functional;

void DecoderOptions::visit(ConfigVisitor& v) {
  v.field("mode", mode,
          "dense (a per-pixel conv head whose maps each support reads; the default, lab/2026-12-06-lpips-gap), "
          "implicit (the paper's feature queries and MLP), none (base Gaussians only: 'w/o learned updates')",
          {"implicit", "dense", "none"});
  v.field("hidden", hidden, "implicit mode: MLP hidden widths; empty = [C, C/4, C/16] from the fused width C",
          Range::between(1, 16384));
  v.field("chunk", chunk, "implicit mode: supports decoded per chunk (bounds memory)", Range::at_least(1));
}

namespace {
// The queries read a texel's channels contiguously. Made channel-last once per forward, no decoder chunk copies
// the maps again (10 MB per chunk at ViT-S width and 256x192).
torch::Tensor channels_last(const torch::Tensor& map) {
  return map.contiguous(torch::MemoryFormat::ChannelsLast);
}
}  // namespace

torch::Tensor query_features(const torch::Tensor& features, const torch::Tensor& uv, int64_t width, int64_t height) {
  ISPLAT_CHECK(features.dim() == 4 && features.size(0) == 1, "query_features: features must be [1,C,h,w], got ",
               features.sizes());
  const double lim = 1.0 - 1e-6;
  auto x = torch::clamp(uv.select(1, 0) * (2.0 / width) - 1.0, -lim, lim);
  auto y = torch::clamp(uv.select(1, 1) * (2.0 / height) - 1.0, -lim, lim);
  auto grid = torch::stack({x, y}, -1).view({1, 1, -1, 2}).to(features.dtype());
  auto out = F::grid_sample(
      features, grid,
      F::GridSampleFuncOptions().mode(torch::kBilinear).padding_mode(torch::kBorder).align_corners(false));
  return out.view({features.size(1), -1}).t();  // [N,C]
}

ImplicitDecoderImpl::ImplicitDecoderImpl(const DecoderOptions& o, int64_t dd, int64_t cd)
    : dino_dim(dd), cnn_dim(cd), chunk(o.chunk) {
  ISPLAT_CHECK(dd > 0 || cd > 0, "decoder: both encoder branches are off");
  const int64_t fused_dim = dd > 0 ? dd : cd;
  if (dd > 0 && cd > 0) {
    cnn_proj = register_module("cnn_proj", nn::Linear(cd, dd));
    gate = register_module("gate", nn::Linear(2 * dd, dd));
  }
  std::vector<int64_t> hidden = o.hidden;
  if (hidden.empty()) hidden = {fused_dim, std::max<int64_t>(16, fused_dim / 4), std::max<int64_t>(16, fused_dim / 16)};
  mlp = register_module("mlp", nn::ModuleList());
  int64_t in = fused_dim;
  for (int64_t h : hidden) {
    mlp->push_back(nn::Linear(in, h));
    in = h;
  }
  head = register_module("head", nn::Linear(in, kDeltaDim));
  torch::NoGradGuard g;
  head->weight.zero_();  // step 0 renders the base Gaussians
  head->bias.zero_();
}

torch::Tensor ImplicitDecoderImpl::decode_features(const torch::Tensor& f_dino, const torch::Tensor& f_cnn) {
  torch::Tensor h;
  if (dino_dim > 0 && cnn_dim > 0) {
    auto c = cnn_proj->forward(f_cnn);
    auto g = torch::sigmoid(gate->forward(torch::cat({f_dino, c}, 1)));
    h = g * f_dino + (1 - g) * c;
  } else {
    h = dino_dim > 0 ? f_dino : f_cnn;
  }
  return mlp_head(h);
}

torch::Tensor ImplicitDecoderImpl::mlp_head(torch::Tensor h) {
  for (auto& layer : *mlp) h = torch::relu(layer->as<nn::Linear>()->forward(h));
  return head->forward(h);
}

torch::Tensor ImplicitDecoderImpl::forward(const torch::Tensor& uv, int64_t width, int64_t height,
                                           const EncoderFeatures& f) {
  const int64_t N = uv.size(0);
  // cnn_proj and the gate's input layer are linear, and bilinear sampling is a convex combination, so
  // they commute: apply them once per feature texel, then sample. Same result as decode_features() on
  // sampled features, at a fraction of the cost (thousands of texels instead of 10^5..10^6 supports).
  std::function<torch::Tensor(const torch::Tensor&)> fused;  // the fused feature [n,C] of a chunk of supports
  torch::Tensor dino, cproj, g_dino, g_cnn;
  torch::Tensor map;
  {
    const Fp32Region fp32;  // the per-texel maps feed our float sampling kernels (the MLP below may run in bf16)
    if (dino_dim > 0 && cnn_dim > 0) {
      dino = f.dino.narrow(0, 0, 1);
      auto as_conv = [](const torch::Tensor& w) { return w.view({w.size(0), w.size(1), 1, 1}); };
      cproj = F::conv2d(f.cnn.narrow(0, 0, 1), as_conv(cnn_proj->weight), F::Conv2dFuncOptions().bias(cnn_proj->bias));
      auto wg = gate->weight;  // [Cd, 2Cd] acting on [f_dino, c']
      g_dino = F::conv2d(dino, as_conv(wg.narrow(1, 0, dino_dim)));
      g_cnn = F::conv2d(cproj, as_conv(wg.narrow(1, dino_dim, dino_dim)), F::Conv2dFuncOptions().bias(gate->bias));
      dino = channels_last(dino), g_dino = channels_last(g_dino), cproj = channels_last(cproj),
      g_cnn = channels_last(g_cnn);
      fused = [&](const torch::Tensor& part) { return gated_sample(dino, g_dino, cproj, g_cnn, part, width, height); };
    } else {  // one branch: its features are h
      map = channels_last((dino_dim > 0 ? f.dino : f.cnn).narrow(0, 0, 1));
      fused = [&](const torch::Tensor& part) { return sample_features(map, part, width, height); };
    }
  }
  std::vector<torch::Tensor> out;
  for (int64_t s = 0; s < N; s += chunk) {
    const int64_t n = std::min(chunk, N - s);
    out.push_back(mlp_head(fused(uv.narrow(0, s, n))));
  }
  return out.size() == 1 ? out[0] : torch::cat(out, 0);
}

}  // namespace isplat
