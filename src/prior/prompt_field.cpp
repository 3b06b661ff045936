// A field fitted to sparse prompts coarse to fine (Gaussian kernels over square buckets, optionally joint bilateral
// on a guide, cross-validated level count); the sparse prior's alignment and densification both use it.
#include "prior/prompt_field.h"

#include <ATen/Parallel.h>
#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>

#include "geometry/bilinear.h"
#include "geometry/camera_torch.h"

namespace isplat {
namespace priors {
namespace {

// Gaussian-kernel mean of per-prompt values over the prompts within 4 sigma, found through square buckets:
// sum w v / (sum w + 1e-3), so far from every prompt a level adds nothing. With a guide and a range > 0, w also
// falls with the guide's gap between prompt and query (a joint bilateral kernel).
class PromptKernel {
 public:
  PromptKernel(const float* prompts, const std::vector<int64_t>& ids, const std::vector<double>& values, double sigma,
               const PromptGuide& guide)
      : p_(prompts),
        values_(values),
        guide_(guide.on() ? &guide.at_prompts : nullptr),
        channels_(guide.channels),
        radius_(4 * sigma),
        inv2s2_(1 / (2 * sigma * sigma)),
        inv2r2_(guide.on() ? 1 / (2 * guide.range * guide.range) : 0) {
    double max_u = 0, max_v = 0;
    for (int64_t i : ids) max_u = std::max<double>(max_u, p_[3 * i]), max_v = std::max<double>(max_v, p_[3 * i + 1]);
    nx_ = static_cast<int64_t>(max_u / radius_) + 1, ny_ = static_cast<int64_t>(max_v / radius_) + 1;
    buckets_.resize(static_cast<size_t>(nx_ * ny_));
    for (int64_t i : ids)
      buckets_[static_cast<size_t>(bucket(p_[3 * i + 1], ny_) * nx_ + bucket(p_[3 * i], nx_))].push_back(i);
  }
  double at(double u, double v, const double* g) const {
    const int64_t bx = bucket(u, nx_), by = bucket(v, ny_);
    double sw = 0, s = 0;
    for (int64_t y = std::max<int64_t>(0, by - 1); y <= std::min(ny_ - 1, by + 1); ++y)
      for (int64_t x = std::max<int64_t>(0, bx - 1); x <= std::min(nx_ - 1, bx + 1); ++x)
        for (int64_t i : buckets_[static_cast<size_t>(y * nx_ + x)]) {
          const double du = p_[3 * i] - u, dv = p_[3 * i + 1] - v, r2 = du * du + dv * dv;
          if (r2 > radius_ * radius_) continue;
          double e = r2 * inv2s2_;
          if (guide_) {
            double gap2 = 0;
            for (int c = 0; c < channels_; ++c) {
              const double dg = (*guide_)[static_cast<size_t>(i * channels_ + c)] - g[c];
              gap2 += dg * dg;
            }
            e += gap2 * inv2r2_;
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
  int channels_;
  double radius_, inv2s2_, inv2r2_;
  int64_t nx_ = 1, ny_ = 1;
  std::vector<std::vector<int64_t>> buckets_;
};

}  // namespace

PromptField fit_prompt_field(const float* p, int64_t P, int64_t H, int64_t W, const std::vector<double>& values,
                             const PromptGuide& guide, const std::vector<double>& sigmas, bool cross_validate,
                             bool want_heldout) {
  const int C = guide.on() ? guide.channels : 0;
  auto prompt_guide = [&](int64_t i) { return C ? &guide.at_prompts[static_cast<size_t>(i * C)] : nullptr; };
  PromptField out;
  int64_t levels = static_cast<int64_t>(sigmas.size());
  if ((cross_validate && levels > 1) || want_heldout) {
    // 5 folds in a fixed shuffled order; the held-out error after each level, summed over folds.
    std::vector<int64_t> order(P);
    std::iota(order.begin(), order.end(), 0);
    std::mt19937_64 rng(0x5EED);
    for (int64_t k = P - 1; k > 0; --k) std::swap(order[k], order[rng() % static_cast<uint64_t>(k + 1)]);
    std::vector<int> fold(P);
    for (int64_t k = 0; k < P; ++k) fold[order[k]] = static_cast<int>(k % 5);
    std::vector<double> error(sigmas.size(), 0.0);
    std::vector<std::vector<double>> heldout(want_heldout ? sigmas.size() : 0, std::vector<double>(P, 0.0));
    for (int f = 0; f < 5; ++f) {
      std::vector<int64_t> train;
      for (int64_t i = 0; i < P; ++i)
        if (fold[i] != f) train.push_back(i);
      std::vector<double> fit(P, 0.0), residual(P);
      for (size_t l = 0; l < sigmas.size(); ++l) {
        for (int64_t i = 0; i < P; ++i) residual[i] = values[i] - fit[i];
        const PromptKernel kernel(p, train, residual, sigmas[l], guide);
        for (int64_t i = 0; i < P; ++i) fit[i] += kernel.at(p[3 * i], p[3 * i + 1], prompt_guide(i));
        for (int64_t i = 0; i < P; ++i)
          if (fold[i] == f) {
            error[l] += std::fabs(values[i] - fit[i]);
            if (want_heldout) heldout[l][static_cast<size_t>(i)] = fit[i];
          }
      }
    }
    if (cross_validate && levels > 1) levels = std::min_element(error.begin(), error.end()) - error.begin() + 1;
    if (want_heldout) out.heldout = heldout[static_cast<size_t>(levels - 1)];
  }
  out.levels = levels;
  std::vector<int64_t> all(P);
  std::iota(all.begin(), all.end(), 0);
  std::vector<double> fit(P, 0.0), residual(P);
  auto correction = torch::zeros({H, W});
  for (int64_t l = 0; l < levels; ++l) {
    for (int64_t i = 0; i < P; ++i) residual[i] = values[i] - fit[i];
    const PromptKernel kernel(p, all, residual, sigmas[l], guide);
    for (int64_t i = 0; i < P; ++i) fit[i] += kernel.at(p[3 * i], p[3 * i + 1], prompt_guide(i));
    // The level's field on a grid fine enough for its width, upsampled bilinearly (jointly bilateral with a guide).
    const int64_t cell = std::clamp<int64_t>(static_cast<int64_t>(sigmas[l] / 2), 1, 8);
    const int64_t gh = (H + cell - 1) / cell, gw = (W + cell - 1) / cell;
    auto field = torch::empty({1, 1, gh, gw});
    float* fp = field.data_ptr<float>();
    std::vector<double> grid_guide(C ? static_cast<size_t>(gh * gw * C) : 0);
    at::parallel_for(0, gh, 1, [&](int64_t y0, int64_t y1) {
      for (int64_t gy = y0; gy < y1; ++gy)
        for (int64_t gx = 0; gx < gw; ++gx) {
          const double u = (gx + 0.5) * cell, v = (gy + 0.5) * cell;
          double* g = nullptr;
          if (C) guide.at(u, v, g = &grid_guide[static_cast<size_t>((gy * gw + gx) * C)]);
          fp[gy * gw + gx] = static_cast<float>(kernel.at(u, v, g));
        }
    });
    if (cell == 1) {
      correction += field[0][0].narrow(0, 0, H).narrow(1, 0, W);
    } else if (!C) {
      correction += resize_bilinear(field, gh * cell, gw * cell)[0][0].narrow(0, 0, H).narrow(1, 0, W);
    } else {
      // Joint bilateral upsampling: the four grid values nearest a pixel count by bilinear weight times the
      // guide's agreement, so a coarse level does not blur a correction across an edge of the guide either.
      float* cp = correction.data_ptr<float>();
      const double inv2r2 = 1 / (2 * guide.range * guide.range);
      const std::vector<double>& pix = *guide.pixels;
      at::parallel_for(0, H, 1, [&](int64_t y0, int64_t y1) {
        for (int64_t y = y0; y < y1; ++y)
          for (int64_t x = 0; x < W; ++x) {
            const double gxf = std::clamp((x + 0.5) / cell - 0.5, 0.0, double(gw - 1));
            const double gyf = std::clamp((y + 0.5) / cell - 0.5, 0.0, double(gh - 1));
            const int64_t ax = static_cast<int64_t>(gxf), ay = static_cast<int64_t>(gyf);
            const int64_t bx = std::min(ax + 1, gw - 1), by = std::min(ay + 1, gh - 1);
            const double fx = gxf - ax, fy = gyf - ay;
            const double* g = &pix[static_cast<size_t>((y * W + x) * C)];
            const int64_t cells[4] = {ay * gw + ax, ay * gw + bx, by * gw + ax, by * gw + bx};
            const double bil[4] = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
            double e[4], e_min = std::numeric_limits<double>::infinity();
            for (int k = 0; k < 4; ++k) {
              double gap2 = 0;
              for (int c = 0; c < C; ++c) {
                const double dg = grid_guide[static_cast<size_t>(cells[k] * C + c)] - g[c];
                gap2 += dg * dg;
              }
              e[k] = gap2 * inv2r2;
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
  out.field = correction;
  return out;
}

}  // namespace priors
}  // namespace isplat
