// Analytic floating-point operation counts of the encoder and decoder (a multiply-add counts 2), and the matmul rate
// this machine reaches at one shape in fp32 or bf16: the benchmarks' counting table (docs/performance.md).
#pragma once
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <vector>

#include <torch/torch.h>

#include "core/progress.h"
#include "model/infinisplat.h"

namespace isplat::bench {

struct StageFlops {
  double vit_linear = 0;     // patch embedding, qkv, projection, MLP of every block
  double vit_attention = 0;  // Q K^T and P V over all heads
  double cnn = 0;            // every convolution of the CNN branch
  double decoder_maps = 0;   // the per-texel projections and gate inputs (implicit), or the dense head's convolutions
  double decoder_mlp = 0;    // the update MLP and head over every support
  double encoder() const { return vit_linear + vit_attention + cnn; }
  double decoder() const { return decoder_maps + decoder_mlp; }
};

// The counts of one prediction of a W x H image with `supports` supports (the ViT counted for semantic = vit only).
inline StageFlops count_flops(const ModelOptions& o, int64_t W, int64_t H, int64_t supports) {
  StageFlops f;
  const auto& e = o.encoder;
  const int64_t h16 = H / 16, w16 = W / 16, H4 = (H + 3) / 4, W4 = (W + 3) / 4;
  const int64_t dd = e.dino ? e.vit.dim() : 0, cd = e.cnn ? e.cnn_options.out_channels : 0;
  if (e.dino && e.semantic == "vit") {
    const double C = static_cast<double>(dd), N = static_cast<double>(h16 * w16 + 1 + e.vit.registers);
    f.vit_linear = 2.0 * h16 * w16 * (3 * 16 * 16) * C + e.vit.blocks() * 24.0 * N * C * C;
    f.vit_attention = e.vit.blocks() * 4.0 * N * N * C;
  }
  if (e.cnn) {
    const int64_t w = e.cnn_options.width;
    auto half = [](int64_t n) { return (n + 1) / 2; };  // stride 2 with "same" padding
    int64_t h = half(H), wd = half(W), in = w;
    f.cnn = 2.0 * h * wd * w * 3 * 49;  // the 7x7 stem
    const int64_t widths[4] = {w, 2 * w, 3 * w, 4 * w}, strides[4] = {1, 2, 2, 2};
    for (int s = 0; s < 4; ++s) {
      if (strides[s] == 2) h = half(h), wd = half(wd);
      const double px = static_cast<double>(h * wd), out = static_cast<double>(widths[s]);
      f.cnn += 2.0 * px * out * in * 9 + 2.0 * px * out * out * 9;           // first block: conv1, conv2
      if (strides[s] != 1 || in != widths[s]) f.cnn += 2.0 * px * out * in;  // its 1x1 shortcut
      f.cnn += 2 * (2.0 * px * out * out * 9);                               // second block
      in = widths[s];
    }
    f.cnn += 2.0 * H4 * W4 * cd * (10 * w) * 9 + 2.0 * H4 * W4 * cd * cd;  // fuse 3x3, project 1x1
  }
  if (o.decoder.mode == "implicit") {
    const int64_t fused = dd > 0 ? dd : cd;
    if (dd > 0 && cd > 0)
      f.decoder_maps = 2.0 * H4 * W4 * cd * dd + 2.0 * h16 * w16 * dd * dd + 2.0 * H4 * W4 * dd * dd;
    std::vector<int64_t> widths = o.decoder.hidden;
    if (widths.empty()) widths = {fused, std::max<int64_t>(16, fused / 4), std::max<int64_t>(16, fused / 16)};
    double macs = 0;
    int64_t in = fused;
    for (int64_t width : widths) macs += static_cast<double>(in) * width, in = width;
    macs += static_cast<double>(in) * kDeltaDim;
    f.decoder_mlp = 2.0 * macs * supports;
  } else if (o.decoder.mode == "dense") {  // decoder/dense_head.h; the supports read its maps
    const double w = kDenseHeadWidth, H2 = static_cast<double>((H + 1) / 2), W2 = static_cast<double>((W + 1) / 2);
    f.decoder_maps = 2.0 * H4 * W4 * (dd + cd) * w * 9 + 2.0 * H2 * W2 * w * w * 9 + 2.0 * H * W * w * (w / 2) * 9 +
                     2.0 * H * W * (w / 2) * kDeltaDim;
  }
  return f;
}

// GFLOP/s of `flop` operations done by `work`: the median of `runs` timed calls after one warm-up.
template <class Work>
double median_gflops(double flop, int runs, const Work& work) {
  torch::NoGradGuard g;
  std::vector<double> ms;
  for (int r = 0; r <= runs; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    work();
    if (r > 0) ms.push_back(ms_since(t0));
  }
  std::sort(ms.begin(), ms.end());
  return flop / (ms[ms.size() / 2] * 1e6);
}

// GFLOP/s of y = x W^T with x [m, k] and W [n, k] in `dtype`.
inline double linear_gflops(int64_t m, int64_t k, int64_t n, torch::Dtype dtype, int runs = 5) {
  const auto x = torch::randn({m, k}).to(dtype), w = torch::randn({n, k}).to(dtype);
  return median_gflops(2.0 * m * k * n, runs, [&] { torch::nn::functional::linear(x, w); });
}

// GFLOP/s of the attention's score product Q K^T for `heads` heads of width `head_dim` over n tokens (rows in
// blocks of at most `rows`), in `dtype`.
inline double attention_gflops(int64_t heads, int64_t n, int64_t head_dim, int64_t rows, torch::Dtype dtype,
                               int runs = 3) {
  const auto q = torch::randn({1, heads, n, head_dim}).to(dtype), kt = torch::randn({1, heads, head_dim, n}).to(dtype);
  return median_gflops(2.0 * heads * n * n * head_dim, runs, [&] {
    for (int64_t s = 0; s < n; s += rows) torch::matmul(q.narrow(2, s, std::min(rows, n - s)), kt);
  });
}

}  // namespace isplat::bench
