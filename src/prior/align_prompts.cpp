// The sparse prior's prompt alignment: a global scale/shift in inverse depth, then a residual log-scale field fitted
// coarse to fine from the prompts (prompt_field.cpp: cross-validated, optionally edge-aware on the log depth).
#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "geometry/bilinear.h"
#include "prior/depth_prior.h"
#include "prior/prompt_field.h"

namespace isplat {
namespace priors {

torch::Tensor align_global(const torch::Tensor& mono_depth, const torch::Tensor& prompts, bool* shaped) {
  auto mono = mono_depth.to(torch::kFloat32).contiguous();
  auto pr = prompts.to(torch::kFloat32).contiguous();
  const int64_t H = mono.size(0), W = mono.size(1), P = pr.size(0);
  const float* m = mono.data_ptr<float>();
  const float* p = pr.data_ptr<float>();
  // 1. Global scale/shift in inverse depth: a * r + b = 1/z, least squares with one trimming pass.
  std::vector<double> r(P), t(P);
  for (int64_t i = 0; i < P; ++i) {
    r[i] = 1.0 / std::max(1e-6f, bilinear_at(m, H, W, p[3 * i], p[3 * i + 1]));
    t[i] = 1.0 / std::max(1e-6f, p[3 * i + 2]);
  }
  std::vector<char> use(P, 1);
  double a = 1, b = 0;
  for (int pass = 0; pass < 2; ++pass) {
    double sr = 0, st = 0, srr = 0, srt = 0, n = 0;
    for (int64_t i = 0; i < P; ++i)
      if (use[i]) sr += r[i], st += t[i], srr += r[i] * r[i], srt += r[i] * t[i], n += 1;
    const double den = n * srr - sr * sr;
    const bool fit = n >= 2 && std::fabs(den) > 1e-12 * n * srr;
    if (fit) {
      a = (n * srt - sr * st) / den;
      b = (st - a * sr) / n;
    }
    if (!fit || a < 0) {  // constant mono depth, or an inverted (useless) prior: a pure shift
      a = 0;
      b = st / std::max(1.0, n);
    }
    std::vector<double> res;
    for (int64_t i = 0; i < P; ++i) res.push_back(std::fabs(a * r[i] + b - t[i]));
    std::vector<double> sorted = res;
    std::nth_element(sorted.begin(), sorted.begin() + P / 2, sorted.end());
    const double mad = sorted[P / 2] + 1e-9;
    for (int64_t i = 0; i < P; ++i) use[i] = res[i] <= 4.0 * mad;
  }
  auto aligned = torch::empty({H, W});
  float* al = aligned.data_ptr<float>();
  for (int64_t k = 0; k < H * W; ++k) al[k] = static_cast<float>(1.0 / std::max(1e-4, a / std::max(1e-6f, m[k]) + b));
  if (shaped) *shaped = a > 0;
  return aligned;
}

AlignedPrompts align_with_heldout(const torch::Tensor& mono_depth, const torch::Tensor& prompts,
                                  const SparsePriorOptions& options, bool want_heldout) {
  auto pr = prompts.to(torch::kFloat32).contiguous();
  const int64_t H = mono_depth.size(0), W = mono_depth.size(1), P = pr.size(0);
  const float* p = pr.data_ptr<float>();
  auto aligned = align_global(mono_depth, pr, nullptr);
  const float* al = aligned.data_ptr<float>();
  // 2. Residual log-scale at the prompts, fitted coarse to fine.
  std::vector<double> logs(P);
  PromptGuide guide;
  guide.channels = 1, guide.range = options.depth_range;
  guide.at_prompts.resize(static_cast<size_t>(P));
  for (int64_t i = 0; i < P; ++i) {
    const float at_prompt = std::max(1e-6f, bilinear_at(al, H, W, p[3 * i], p[3 * i + 1]));  // float: as before
    logs[i] = std::log(p[3 * i + 2] / at_prompt);
    guide.at_prompts[i] = std::log(at_prompt);
  }
  std::vector<double> log_aligned(guide.on() ? static_cast<size_t>(H * W) : 0);  // the pixels' guide, once
  for (size_t k = 0; k < log_aligned.size(); ++k) log_aligned[k] = std::log(std::max(1e-6f, al[k]));
  guide.pixels = &log_aligned;
  guide.at = [&](double u, double v, double* g) { g[0] = std::log(std::max(1e-6f, bilinear_at(al, H, W, u, v))); };
  const double diag = std::sqrt(double(H) * H + double(W) * W);
  std::vector<double> sigmas;
  for (double s = options.bandwidth; sigmas.empty() || s >= options.finest * (1 - 1e-9); s /= 2)
    sigmas.push_back(s * diag);
  const PromptField field = fit_prompt_field(p, P, H, W, logs, guide, sigmas, options.cross_validate, want_heldout);
  AlignedPrompts out;
  out.depth = aligned * torch::exp(field.field);
  out.levels = field.levels;
  if (want_heldout) {
    out.heldout_log.resize(static_cast<size_t>(P));
    for (int64_t i = 0; i < P; ++i) out.heldout_log[i] = guide.at_prompts[i] + field.heldout[i];
  }
  return out;
}

}  // namespace priors

torch::Tensor align_to_prompts(const torch::Tensor& mono_depth, const torch::Tensor& prompts,
                               const SparsePriorOptions& options, int64_t* levels_used) {
  priors::AlignedPrompts a = priors::align_with_heldout(mono_depth, prompts, options, false);
  if (levels_used) *levels_used = a.levels;
  return a.depth;
}

}  // namespace isplat
