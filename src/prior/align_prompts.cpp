// The sparse prior's prompt alignment: a global scale/shift in inverse depth, then a residual log-scale field fitted
// coarse to fine from the prompts (cross-validated, optionally edge-aware).
#include <ATen/Parallel.h>
#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>

#include "geometry/bilinear.h"
#include "geometry/camera_torch.h"
#include "prior/depth_prior.h"

namespace isplat {
namespace {

// Gaussian-kernel mean of per-prompt values over the prompts within 4 sigma, found through square buckets:
// sum w v / (sum w + 1e-3), so far from every prompt a level adds nothing. With a guide (log depth per prompt)
// and a range > 0, w also falls with the guide's gap between prompt and query (a joint bilateral kernel).
class PromptKernel {
 public:
  PromptKernel(const float* prompts, const std::vector<int64_t>& ids, const std::vector<double>& values, double sigma,
               const std::vector<double>* guide = nullptr, double range = 0)
      : p_(prompts),
        values_(values),
        guide_(range > 0 ? guide : nullptr),
        radius_(4 * sigma),
        inv2s2_(1 / (2 * sigma * sigma)),
        inv2r2_(range > 0 ? 1 / (2 * range * range) : 0) {
    double max_u = 0, max_v = 0;
    for (int64_t i : ids) max_u = std::max<double>(max_u, p_[3 * i]), max_v = std::max<double>(max_v, p_[3 * i + 1]);
    nx_ = static_cast<int64_t>(max_u / radius_) + 1, ny_ = static_cast<int64_t>(max_v / radius_) + 1;
    buckets_.resize(static_cast<size_t>(nx_ * ny_));
    for (int64_t i : ids)
      buckets_[static_cast<size_t>(bucket(p_[3 * i + 1], ny_) * nx_ + bucket(p_[3 * i], nx_))].push_back(i);
  }
  double at(double u, double v, double g = 0) const {
    const int64_t bx = bucket(u, nx_), by = bucket(v, ny_);
    double sw = 0, s = 0;
    for (int64_t y = std::max<int64_t>(0, by - 1); y <= std::min(ny_ - 1, by + 1); ++y)
      for (int64_t x = std::max<int64_t>(0, bx - 1); x <= std::min(nx_ - 1, bx + 1); ++x)
        for (int64_t i : buckets_[static_cast<size_t>(y * nx_ + x)]) {
          const double du = p_[3 * i] - u, dv = p_[3 * i + 1] - v, r2 = du * du + dv * dv;
          if (r2 > radius_ * radius_) continue;
          double e = r2 * inv2s2_;
          if (guide_) {
            const double dg = (*guide_)[static_cast<size_t>(i)] - g;
            e += dg * dg * inv2r2_;
          }
          const double w = std::exp(-e);
          sw += w, s += w * values_[static_cast<size_t>(i)];
        }
    return s / (sw + 1e-3);
  }

 private:
  int64_t bucket(double c, int64_t n) const { return std::clamp<int64_t>(static_cast<int64_t>(c / radius_), 0, n - 1); }
  const float* p_;
  const std::vector<double>& values_;
  const std::vector<double>* guide_;
  double radius_, inv2s2_, inv2r2_;
  int64_t nx_ = 1, ny_ = 1;
  std::vector<std::vector<int64_t>> buckets_;
};

}  // namespace

torch::Tensor align_to_prompts(const torch::Tensor& mono_depth, const torch::Tensor& prompts,
                               const SparsePriorOptions& options, int64_t* levels_used) {
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
  // 2. Residual log-scale at the prompts, fitted coarse to fine.
  auto aligned = torch::empty({H, W});
  float* al = aligned.data_ptr<float>();
  for (int64_t k = 0; k < H * W; ++k) al[k] = static_cast<float>(1.0 / std::max(1e-4, a / std::max(1e-6f, m[k]) + b));
  std::vector<double> logs(P), guide(P);
  for (int64_t i = 0; i < P; ++i) {
    const float at_prompt = std::max(1e-6f, bilinear_at(al, H, W, p[3 * i], p[3 * i + 1]));  // float: as before
    logs[i] = std::log(p[3 * i + 2] / at_prompt);
    guide[i] = std::log(at_prompt);
  }
  const double range = options.depth_range;
  const double diag = std::sqrt(double(H) * H + double(W) * W);
  std::vector<double> sigmas;
  for (double s = options.bandwidth; sigmas.empty() || s >= options.finest * (1 - 1e-9); s /= 2)
    sigmas.push_back(s * diag);
  int64_t levels = static_cast<int64_t>(sigmas.size());
  if (options.cross_validate && levels > 1) {
    // 5 folds in a fixed shuffled order; the held-out error after each level, summed over folds.
    std::vector<int64_t> order(P);
    std::iota(order.begin(), order.end(), 0);
    std::mt19937_64 rng(0x5EED);
    for (int64_t k = P - 1; k > 0; --k) std::swap(order[k], order[rng() % static_cast<uint64_t>(k + 1)]);
    std::vector<int> fold(P);
    for (int64_t k = 0; k < P; ++k) fold[order[k]] = static_cast<int>(k % 5);
    std::vector<double> error(sigmas.size(), 0.0);
    for (int f = 0; f < 5; ++f) {
      std::vector<int64_t> train;
      for (int64_t i = 0; i < P; ++i)
        if (fold[i] != f) train.push_back(i);
      std::vector<double> fit(P, 0.0), residual(P);
      for (size_t l = 0; l < sigmas.size(); ++l) {
        for (int64_t i = 0; i < P; ++i) residual[i] = logs[i] - fit[i];
        const PromptKernel kernel(p, train, residual, sigmas[l], &guide, range);
        for (int64_t i = 0; i < P; ++i) fit[i] += kernel.at(p[3 * i], p[3 * i + 1], guide[i]);
        for (int64_t i = 0; i < P; ++i)
          if (fold[i] == f) error[l] += std::fabs(logs[i] - fit[i]);
      }
    }
    levels = std::min_element(error.begin(), error.end()) - error.begin() + 1;
  }
  if (levels_used) *levels_used = levels;
  std::vector<int64_t> all(P);
  std::iota(all.begin(), all.end(), 0);
  std::vector<double> fit(P, 0.0), residual(P);
  auto correction = torch::zeros({H, W});
  std::vector<double> log_aligned(range > 0 ? static_cast<size_t>(H * W) : 0);  // the pixels' guide, once
  for (size_t k = 0; k < log_aligned.size(); ++k) log_aligned[k] = std::log(std::max(1e-6f, al[k]));
  for (int64_t l = 0; l < levels; ++l) {
    for (int64_t i = 0; i < P; ++i) residual[i] = logs[i] - fit[i];
    const PromptKernel kernel(p, all, residual, sigmas[l], &guide, range);
    for (int64_t i = 0; i < P; ++i) fit[i] += kernel.at(p[3 * i], p[3 * i + 1], guide[i]);
    // The level's field on a grid fine enough for its width, upsampled bilinearly (jointly bilateral with a range).
    const int64_t cell = std::clamp<int64_t>(static_cast<int64_t>(sigmas[l] / 2), 1, 8);
    const int64_t gh = (H + cell - 1) / cell, gw = (W + cell - 1) / cell;
    auto field = torch::empty({1, 1, gh, gw});
    float* fp = field.data_ptr<float>();
    std::vector<double> grid_guide(range > 0 ? static_cast<size_t>(gh * gw) : 0);
    at::parallel_for(0, gh, 1, [&](int64_t y0, int64_t y1) {
      for (int64_t gy = y0; gy < y1; ++gy)
        for (int64_t gx = 0; gx < gw; ++gx) {
          const double u = (gx + 0.5) * cell, v = (gy + 0.5) * cell;
          double g = 0;
          if (range > 0) g = grid_guide[gy * gw + gx] = std::log(std::max(1e-6f, bilinear_at(al, H, W, u, v)));
          fp[gy * gw + gx] = static_cast<float>(kernel.at(u, v, g));
        }
    });
    if (cell == 1) {
      correction += field[0][0].narrow(0, 0, H).narrow(1, 0, W);
    } else if (range == 0) {
      correction += resize_bilinear(field, gh * cell, gw * cell)[0][0].narrow(0, 0, H).narrow(1, 0, W);
    } else {
      // Joint bilateral upsampling: the four grid values nearest a pixel count by bilinear weight times the
      // guide's agreement, so a coarse level does not blur a correction across a depth edge either.
      float* cp = correction.data_ptr<float>();
      const double inv2r2 = 1 / (2 * range * range);
      at::parallel_for(0, H, 1, [&](int64_t y0, int64_t y1) {
        for (int64_t y = y0; y < y1; ++y)
          for (int64_t x = 0; x < W; ++x) {
            const double gxf = std::clamp((x + 0.5) / cell - 0.5, 0.0, double(gw - 1));
            const double gyf = std::clamp((y + 0.5) / cell - 0.5, 0.0, double(gh - 1));
            const int64_t ax = static_cast<int64_t>(gxf), ay = static_cast<int64_t>(gyf);
            const int64_t bx = std::min(ax + 1, gw - 1), by = std::min(ay + 1, gh - 1);
            const double fx = gxf - ax, fy = gyf - ay;
            const double g = log_aligned[static_cast<size_t>(y * W + x)];
            const int64_t cells[4] = {ay * gw + ax, ay * gw + bx, by * gw + ax, by * gw + bx};
            const double bil[4] = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
            double e[4], e_min = std::numeric_limits<double>::infinity();
            for (int k = 0; k < 4; ++k) {
              const double dg = grid_guide[static_cast<size_t>(cells[k])] - g;
              e[k] = dg * dg * inv2r2;
              if (bil[k] > 0) e_min = std::min(e_min, e[k]);
            }
            // A pixel unlike all four grid points (more than two ranges away: a pole or gap narrower than a
            // cell) gets the level evaluated at itself, so it keeps its own surface's correction.
            if (e_min > 2) {
              cp[y * W + x] += static_cast<float>(kernel.at(x + 0.5, y + 0.5, g));
              continue;
            }
            double sw = 0, s = 0;  // exponents relative to the closest guide, so the weights cannot all underflow
            for (int k = 0; k < 4; ++k) {
              if (bil[k] <= 0) continue;
              const double w = bil[k] * std::exp(e_min - e[k]);
              sw += w, s += w * fp[cells[k]];
            }
            cp[y * W + x] += static_cast<float>(s / sw);
          }
      });
    }
  }
  return aligned * torch::exp(correction);
}

}  // namespace isplat
