// Tuple augmentation: shared photometric jitter, per-view zoom with intrinsics, and a consistent mirror.
#include "data/augment.h"

#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "core/config.h"
#include "data/tuples.h"
#include "geometry/camera_torch.h"

namespace isplat {
namespace F = torch::nn::functional;

bool AugmentOptions::any() const {
  return flip > 0 || zoom > 0 || brightness > 0 || contrast > 0 || saturation > 0 || gamma > 0 ||
         channel_shuffle > 0 || gray > 0;
}

void AugmentOptions::visit(ConfigVisitor& v) {
  v.field("flip", flip, "probability of mirroring a training tuple left-right (images, depth, intrinsics, poses)",
          Range::unit());
  v.field("zoom", zoom,
          "zoom each view by z uniform in [1, 1+zoom]: crop 1/z of each side at a random place, resize back, "
          "scale the focal length (0 = off)",
          Range::between(0, 3));
  v.field("brightness", brightness, "colour gain log-uniform in [1/(1+b), 1+b], the same for every view (0 = off)",
          Range::between(0, 3));
  v.field("contrast", contrast, "contrast about mid-grey, factor log-uniform in [1/(1+c), 1+c] (0 = off)",
          Range::between(0, 3));
  v.field("saturation", saturation, "saturation factor log-uniform in [1/(1+s), 1+s] (0 = off)", Range::between(0, 3));
  v.field("gamma", gamma, "gamma exponent log-uniform in [1/(1+g), 1+g] (0 = off)", Range::between(0, 3));
  v.field("channel_shuffle", channel_shuffle, "probability of permuting R, G and B (the same for every view)",
          Range::unit());
  v.field("gray", gray, "probability of turning the whole tuple greyscale", Range::unit());
}

namespace {

// A factor log-uniform in [1/(1+a), 1+a], or 1 when a = 0 (then nothing is drawn).
double log_uniform(double a, std::mt19937_64& rng) {
  if (a <= 0) return 1.0;
  const double r = std::log1p(a);
  return std::exp(std::uniform_real_distribution<double>(-r, r)(rng));
}

bool chance(double p, std::mt19937_64& rng) { return p > 0 && std::uniform_real_distribution<double>(0, 1)(rng) < p; }

struct Photometric {
  double gain = 1, contrast = 1, saturation = 1, gamma = 1;
  bool gray = false;
  std::vector<int64_t> order = {0, 1, 2};
  bool identity() const {
    return gain == 1 && contrast == 1 && saturation == 1 && gamma == 1 && !gray && order == std::vector<int64_t>{0, 1, 2};
  }
};

torch::Tensor luma(const torch::Tensor& image) {  // [3,H,W] -> [1,H,W], Rec. 601 weights
  return (0.299 * image[0] + 0.587 * image[1] + 0.114 * image[2]).unsqueeze(0);
}

torch::Tensor apply_photometric(torch::Tensor image, const Photometric& p) {
  if (p.gamma != 1) image = image.clamp_min(0).pow(p.gamma);
  if (p.gain != 1) image = image * p.gain;
  if (p.contrast != 1) image = (image - 0.5) * p.contrast + 0.5;
  if (p.saturation != 1) {
    const auto y = luma(image);
    image = y + (image - y) * p.saturation;
  }
  if (p.order != std::vector<int64_t>{0, 1, 2}) image = image.index_select(0, torch::tensor(p.order));
  if (p.gray) image = luma(image).expand({3, -1, -1});
  return image.clamp(0, 1).contiguous();
}

torch::Tensor resize_nearest(const torch::Tensor& map, int64_t height, int64_t width) {  // [H,W]
  return F::interpolate(map.unsqueeze(0).unsqueeze(0),
                        F::InterpolateFuncOptions().size(std::vector<int64_t>{height, width}).mode(torch::kNearest))
      .squeeze(0)
      .squeeze(0);
}

void zoom_view(ViewTensors& view, double z, double fx, double fy) {
  const int64_t H = view.image.size(1), W = view.image.size(2);
  const int64_t cw = std::max<int64_t>(1, std::lround(W / z)), ch = std::max<int64_t>(1, std::lround(H / z));
  const int64_t x0 = std::lround(fx * (W - cw)), y0 = std::lround(fy * (H - ch));
  auto [cropped, K] = crop_with_K(view.image, view.camera.K, x0, y0, cw, ch);
  std::tie(view.image, view.camera.K) = resize_with_K(cropped, K, H, W);
  view.image = view.image.clamp(0, 1).contiguous();
  if (view.depth.defined() && view.depth.numel() > 0) {
    view.depth = resize_nearest(view.depth.narrow(0, y0, ch).narrow(1, x0, cw), H, W).contiguous();
    view.valid = resize_nearest(view.valid.narrow(0, y0, ch).narrow(1, x0, cw), H, W).contiguous();
  }
}

// Mirror x in camera space: image columns reversed, cx -> W - cx (pixel centres at j + 0.5), and the pose
// conjugated by diag(-1, 1, 1, 1), which mirrors the world too, so every view of the tuple stays consistent.
void mirror_view(ViewTensors& view) {
  const int64_t W = view.image.size(2);
  view.image = view.image.flip({2}).contiguous();
  if (view.depth.defined() && view.depth.numel() > 0) {
    view.depth = view.depth.flip({1}).contiguous();
    view.valid = view.valid.flip({1}).contiguous();
  }
  auto K = view.camera.K.clone();
  K[0][2] = static_cast<double>(W) - K[0][2];
  K[0][1] = -K[0][1];
  view.camera.K = K;
  const auto M = torch::diag(torch::tensor({-1.0, 1.0, 1.0, 1.0}, view.camera.T_cw.options()));
  view.camera.T_cw = torch::matmul(torch::matmul(M, view.camera.T_cw), M);
}

}  // namespace

void augment_tuple(TupleSample& sample, const AugmentOptions& o, uint64_t seed) {
  if (!o.any()) return;
  std::mt19937_64 rng(seed);
  // Draw every decision up front in a fixed order, so a tuple's augmentation depends only on the seed.
  Photometric p;
  p.gamma = log_uniform(o.gamma, rng);
  p.gain = log_uniform(o.brightness, rng);
  p.contrast = log_uniform(o.contrast, rng);
  p.saturation = log_uniform(o.saturation, rng);
  if (chance(o.channel_shuffle, rng)) std::shuffle(p.order.begin(), p.order.end(), rng);
  p.gray = chance(o.gray, rng);
  const bool mirror = chance(o.flip, rng);
  std::vector<ViewTensors*> views = {&sample.context};
  for (auto& t : sample.targets) views.push_back(&t);
  for (ViewTensors* v : views) {
    if (o.zoom > 0) {
      std::uniform_real_distribution<double> u(0, 1);
      const double z = 1 + o.zoom * u(rng), fx = u(rng), fy = u(rng);
      zoom_view(*v, z, fx, fy);
    }
    if (!p.identity()) v->image = apply_photometric(v->image, p);
    if (mirror) mirror_view(*v);
  }
}

}  // namespace isplat
