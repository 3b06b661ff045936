// The sparse prior's densification (prior.sparse.densify): today's prior fit, a prompt-only interpolation guided by
// the image, or the prior blended in per region where held-out prompts show it helps; a confidence per pixel and
// the rule for pixels far from every prompt (prior.sparse.far).
#include <torch/torch.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <vector>

#include "core/error.h"
#include "geometry/bilinear.h"
#include "prior/depth_prior.h"
#include "prior/prompt_field.h"

namespace isplat {
namespace {

constexpr double kBlendZ0 = 2.0;          // the prior's wins in a region must be this many standard errors ...
constexpr double kBlendZSpan = 1.0;       // ... above chance for any weight, and this many more for full weight
constexpr double kBlendMinPrompts = 8;    // fewer held-out prompts (effective count) in a region: no prior there
constexpr double kConfidenceError = 0.1;  // a local held-out |log error| of this halves the confidence
constexpr double kBehindRadius = 0.05;    // far = behind: the neighbourhood searched, fraction of the diagonal

void check_prompts(const torch::Tensor& prompts, int64_t H, int64_t W) {
  ISPLAT_CHECK(prompts.defined() && prompts.dim() == 2 && prompts.size(1) == 3,
               "sparse prior: prompts must be [P, 3] (u, v, z), got ",
               prompts.defined() ? prompts.sizes() : torch::IntArrayRef{});
  ISPLAT_CHECK(prompts.size(0) >= 3, "sparse prior: needs at least 3 prompts (u, v, z), got ", prompts.size(0),
               " (empty source depth, or a prompts file without points?)");
  const auto p = prompts.to(torch::kFloat32);
  const auto z = p.select(1, 2), u = p.select(1, 0), v = p.select(1, 1);
  const auto bad_z = torch::logical_not(torch::isfinite(z) & (z > 0));
  ISPLAT_CHECK(!bad_z.any().item<bool>(), "sparse prior: ", bad_z.sum().item<int64_t>(),
               " prompts have a depth that is not finite and positive (first: z = ",
               z.masked_select(bad_z)[0].item<double>(), ")");
  const auto outside =
      torch::logical_not(torch::isfinite(u) & torch::isfinite(v) & (u >= 0) & (u <= W) & (v >= 0) & (v <= H));
  ISPLAT_CHECK(!outside.any().item<bool>(), "sparse prior: ", outside.sum().item<int64_t>(),
               " prompts lie outside the ", W, "x", H, " image (u in [0, W], v in [0, H] pixels)");
}

std::vector<double> level_sigmas(const SparsePriorOptions& o, int64_t H, int64_t W) {
  const double diag = std::sqrt(double(H) * H + double(W) * W);
  std::vector<double> sigmas;
  for (double s = o.bandwidth; sigmas.empty() || s >= o.finest * (1 - 1e-9); s /= 2) sigmas.push_back(s * diag);
  return sigmas;
}

// Log depth interpolated from the prompts, coarse to fine and edge-aware in the image's colour, about a base: the
// prompts' median log depth (the prompts alone), or the log of `aligned`, a monocular depth globally aligned to them
// (the prior's shape, with its log depth as a fourth guide channel scaled by color_range / depth_range, so the field
// also stops at the prior's depth edges). A constant `aligned` gives the prompts-alone field up to the base.
priors::AlignedPrompts image_guided(const torch::Tensor& image, const float* p, int64_t P, const SparsePriorOptions& o,
                                    const torch::Tensor* aligned) {
  const int64_t H = image.size(1), W = image.size(2);
  auto img = image.to(torch::kFloat32).contiguous();
  const float* ip = img.data_ptr<float>();
  torch::Tensor log_base;
  if (aligned) {
    log_base = torch::log(aligned->clamp_min(1e-6)).contiguous();
  } else {
    std::vector<double> logs(P);
    for (int64_t i = 0; i < P; ++i) logs[i] = std::log(static_cast<double>(p[3 * i + 2]));
    std::nth_element(logs.begin(), logs.begin() + P / 2, logs.end());
    log_base = torch::full({H, W}, logs[P / 2]);
  }
  const float* bp = log_base.data_ptr<float>();
  const int C = aligned && o.depth_range > 0 ? 4 : 3;
  const double depth_scale = aligned && o.depth_range > 0 ? o.color_range / o.depth_range : 0;
  std::vector<double> values(P), base_at(P);
  for (int64_t i = 0; i < P; ++i) {
    base_at[i] = bilinear_at(bp, H, W, p[3 * i], p[3 * i + 1]);
    values[i] = std::log(static_cast<double>(p[3 * i + 2])) - base_at[i];
  }
  priors::PromptGuide guide;
  guide.channels = C, guide.range = o.color_range;
  auto guide_at = [&](double u, double v, double* g) {
    for (int c = 0; c < 3; ++c) g[c] = bilinear_at(ip + c * H * W, H, W, u, v);
    if (C == 4) g[3] = depth_scale * bilinear_at(bp, H, W, u, v);
  };
  guide.at = guide_at;
  guide.at_prompts.resize(static_cast<size_t>(C * P));
  for (int64_t i = 0; i < P; ++i) guide_at(p[3 * i], p[3 * i + 1], &guide.at_prompts[static_cast<size_t>(C * i)]);
  std::vector<double> pixels(static_cast<size_t>(C * H * W));
  for (int64_t k = 0; k < H * W; ++k) {
    for (int c = 0; c < 3; ++c) pixels[static_cast<size_t>(C * k + c)] = ip[c * H * W + k];
    if (C == 4) pixels[static_cast<size_t>(C * k + 3)] = depth_scale * bp[k];
  }
  guide.pixels = &pixels;
  const priors::PromptField f =
      priors::fit_prompt_field(p, P, H, W, values, guide, level_sigmas(o, H, W), o.cross_validate, true);
  priors::AlignedPrompts out;
  out.depth = torch::exp(f.field + log_base);  // [H,W]
  out.levels = f.levels;
  out.heldout_log.resize(static_cast<size_t>(P));
  for (int64_t i = 0; i < P; ++i) out.heldout_log[i] = base_at[i] + f.heldout[i];
  return out;
}

// Per-region share of the prior fit: tiles of the coarsest kernel's width; each tile pools its prompts and its 8
// neighbours' (Gaussian weights) and compares the two densifications' held-out |log error| prompt by prompt. The
// prior counts only where it cuts the error on more prompts than chance would (a sign test, robust to the few large
// errors at depth edges) and on average: z = (wins - n/2) / sqrt(n/4) of kBlendZ0 gives weight 0, kBlendZ0 +
// kBlendZSpan weight 1, linear between; a mean gain <= 0 or fewer than kBlendMinPrompts (effective) prompts: 0.
// Bilinear between tile centres. Also the local held-out error of the result per pixel.
void blend_weights(const float* p, int64_t P, int64_t H, int64_t W, const std::vector<double>& err_img,
                   const std::vector<double>* err_fit, double tile, torch::Tensor& weight, torch::Tensor& error) {
  const int64_t nx = std::max<int64_t>(1, static_cast<int64_t>(std::ceil(W / tile)));
  const int64_t ny = std::max<int64_t>(1, static_cast<int64_t>(std::ceil(H / tile)));
  // per tile: count, sum of the image's and the fit's errors, the fit's wins (ties count half)
  std::vector<double> n(nx * ny, 0.0), s_img(nx * ny, 0.0), s_fit(nx * ny, 0.0), s_win(nx * ny, 0.0);
  for (int64_t i = 0; i < P; ++i) {
    const int64_t tx = std::clamp<int64_t>(static_cast<int64_t>(p[3 * i] / tile), 0, nx - 1);
    const int64_t ty = std::clamp<int64_t>(static_cast<int64_t>(p[3 * i + 1] / tile), 0, ny - 1);
    const int64_t t = ty * nx + tx;
    const double fit = err_fit ? (*err_fit)[i] : err_img[i];
    n[t] += 1, s_img[t] += err_img[i], s_fit[t] += fit;
    s_win[t] += fit < err_img[i] ? 1.0 : fit == err_img[i] ? 0.5 : 0.0;
  }
  // The prior must also win over the whole image (the same sign test on every prompt), so a useless prior's lucky
  // regions do not count.
  double wins = 0;
  for (double w : s_win) wins += w;
  const bool global =
      err_fit && (wins / P - 0.5) * 2 * std::sqrt(double(P)) >= kBlendZ0 &&
      std::accumulate(s_fit.begin(), s_fit.end(), 0.0) < std::accumulate(s_img.begin(), s_img.end(), 0.0);
  std::vector<float> w_tile(nx * ny, 0.0f), e_tile(nx * ny, 0.0f);
  for (int64_t ty = 0; ty < ny; ++ty)
    for (int64_t tx = 0; tx < nx; ++tx) {
      double sg = 0, sgg = 0, si = 0, sf = 0, sw = 0;
      for (int64_t dy = -1; dy <= 1; ++dy)
        for (int64_t dx = -1; dx <= 1; ++dx) {
          const int64_t x = tx + dx, y = ty + dy;
          if (x < 0 || y < 0 || x >= nx || y >= ny) continue;
          const int64_t t = y * nx + x;
          const double g = std::exp(-0.5 * double(dx * dx + dy * dy));
          sg += g * n[t], sgg += g * g * n[t], si += g * s_img[t], sf += g * s_fit[t], sw += g * s_win[t];
        }
      const double e_img = sg > 0 ? si / sg : 0, e_fit = sg > 0 ? sf / sg : 0;
      double w = 0;
      const double n_eff = sgg > 0 ? sg * sg / sgg : 0;
      if (global && n_eff >= kBlendMinPrompts && e_fit < e_img) {
        const double z = (sw / sg - 0.5) * 2 * std::sqrt(n_eff);  // the win share's z in the effective count
        w = std::clamp((z - kBlendZ0) / kBlendZSpan, 0.0, 1.0);
      }
      w_tile[ty * nx + tx] = static_cast<float>(w);
      e_tile[ty * nx + tx] = static_cast<float>(e_img + w * (e_fit - e_img));
    }
  weight = torch::empty({H, W}), error = torch::empty({H, W});
  float* wp = weight.data_ptr<float>();
  float* ep = error.data_ptr<float>();
  for (int64_t y = 0; y < H; ++y)
    for (int64_t x = 0; x < W; ++x) {  // tile centres at (t + 0.5) * tile: the bilinear lookup's convention
      const double u = (x + 0.5) / tile, v = (y + 0.5) / tile;
      wp[y * W + x] = bilinear_at(w_tile.data(), ny, nx, u, v);
      ep[y * W + x] = bilinear_at(e_tile.data(), ny, nx, u, v);
    }
}

}  // namespace

SparseDensity densify_prompts(const torch::Tensor& image, const torch::Tensor& mono, const torch::Tensor& prompts,
                              const SparsePriorOptions& o) {
  ISPLAT_CHECK(image.defined() && image.dim() == 3 && image.size(0) == 3, "sparse prior: image must be [3, H, W]");
  const int64_t H = image.size(1), W = image.size(2);
  check_prompts(prompts, H, W);
  ISPLAT_CHECK(o.densify == "image" || (mono.defined() && mono.dim() == 2 && mono.size(0) == H && mono.size(1) == W),
               "sparse prior: prior.sparse.densify = ", o.densify, " needs a monocular depth [", H, ", ", W, "]");
  auto pr = prompts.to(torch::kFloat32).contiguous();
  const float* p = pr.data_ptr<float>();
  const int64_t P = pr.size(0);
  SparseDensity out;
  std::vector<double> log_z(P);
  for (int64_t i = 0; i < P; ++i) log_z[i] = std::log(static_cast<double>(p[3 * i + 2]));
  auto errors = [&](const std::vector<double>& heldout) {
    std::vector<double> e(P);
    for (int64_t i = 0; i < P; ++i) e[i] = std::fabs(heldout[i] - log_z[i]);
    return e;
  };
  const double diag = std::sqrt(double(H) * H + double(W) * W);
  const double tile = std::max(8.0, o.bandwidth * diag);
  torch::Tensor error;
  if (o.densify == "fit") {
    const priors::AlignedPrompts fit = priors::align_with_heldout(mono, pr, o, true);
    out.depth = fit.depth, out.levels = fit.levels;
    blend_weights(p, P, H, W, errors(fit.heldout_log), nullptr, tile, out.prior_weight, error);
    out.prior_weight.fill_(1.0);
  } else {
    const priors::AlignedPrompts img = image_guided(image, p, P, o, nullptr);
    out.levels = img.levels;
    const std::vector<double> e_img = errors(img.heldout_log);
    if (o.densify == "image") {
      out.depth = img.depth;
      blend_weights(p, P, H, W, e_img, nullptr, tile, out.prior_weight, error);
    } else {  // blend: the same field about the prior's globally aligned shape, taken where it predicts better
      bool shaped = false;
      const torch::Tensor aligned = priors::align_global(mono, pr, &shaped);
      if (!shaped) {  // a flat or inverted prior has no shape to give
        out.depth = img.depth;
        blend_weights(p, P, H, W, e_img, nullptr, tile, out.prior_weight, error);
      } else {
        const priors::AlignedPrompts fit = image_guided(image, p, P, o, &aligned);
        const std::vector<double> e_fit = errors(fit.heldout_log);
        blend_weights(p, P, H, W, e_img, &e_fit, tile, out.prior_weight, error);
        const auto log_img = torch::log(img.depth);
        out.depth = torch::exp(log_img + out.prior_weight * (torch::log(fit.depth) - log_img));
      }
    }
  }
  // Confidence: exp(-d^2 / (2 s^2)) / (1 + e / kConfidenceError), d the distance to the nearest prompt, s the mean
  // prompt spacing sqrt(HW / P), e the local held-out |log error|.
  cv::Mat free(static_cast<int>(H), static_cast<int>(W), CV_8U, cv::Scalar(255)), dist;
  for (int64_t i = 0; i < P; ++i) {
    const int64_t x = std::clamp<int64_t>(static_cast<int64_t>(p[3 * i]), 0, W - 1);
    const int64_t y = std::clamp<int64_t>(static_cast<int64_t>(p[3 * i + 1]), 0, H - 1);
    free.at<uint8_t>(static_cast<int>(y), static_cast<int>(x)) = 0;
  }
  cv::distanceTransform(free, dist, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  const auto d = torch::from_blob(dist.data, {H, W}, torch::kFloat32).clone();
  const double spacing = std::sqrt(double(H) * W / double(P));
  out.distance = d / spacing;
  out.confidence = torch::exp(-0.5 * out.distance.square()) / (1.0 + error / kConfidenceError);
  const auto far = out.distance > o.far_spacings;
  if (o.far == "drop") {
    out.depth = torch::where(far, torch::zeros_like(out.depth), out.depth);
  } else if (o.far == "behind") {
    // Keep a far pixel only at or behind the farthest supported depth within kBehindRadius of it, so a guessed
    // surface cannot stand in front of what the prompts support nearby; none within it: kept.
    auto supported = torch::where(far, torch::zeros_like(out.depth), out.depth).contiguous();
    cv::Mat s(static_cast<int>(H), static_cast<int>(W), CV_32F, supported.data_ptr<float>()), m;
    const int r = std::max(1, static_cast<int>(std::lround(kBehindRadius * diag)));
    cv::dilate(s, m, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * r + 1, 2 * r + 1)));
    const auto nearest = torch::from_blob(m.data, {H, W}, torch::kFloat32).clone();
    out.depth = torch::where(far & (out.depth < nearest), torch::zeros_like(out.depth), out.depth);
  }
  out.confidence = torch::where(out.depth > 0, out.confidence, torch::zeros_like(out.confidence));
  return out;
}

}  // namespace isplat
