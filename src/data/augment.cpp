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
bool AugmentOptions::any() const {
  return flip > 0 || zoom > 0 || brightness > 0 || contrast > 0 || saturation > 0 || gamma > 0 || channel_shuffle > 0 ||
         gray > 0;
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
  v.field("channel_shuffle", channel_shuffle,
          "probability of shuffling R, G and B, the same for every view (one shuffle in six keeps the order)",
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

bool chance(double p, std::mt19937_64& rng) {
  return p > 0 && std::uniform_real_distribution<double>(0, 1)(rng) < p;
}

struct Photometric {
  double gain = 1, contrast = 1, saturation = 1, gamma = 1;
  bool gray = false;
  std::vector<int64_t> order = {0, 1, 2};
  bool shuffled() const { return order != std::vector<int64_t>{0, 1, 2}; }
  bool identity() const { return gain == 1 && contrast == 1 && saturation == 1 && gamma == 1 && !gray && !shuffled(); }
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
  if (p.shuffled()) image = image.index_select(0, torch::tensor(p.order));
  if (p.gray) image = luma(image).expand({3, -1, -1});
  return image.clamp(0, 1).contiguous();
}

// Depth and validity [2,h,w] resized to [2,H,W] by taking the source pixel under each output pixel's centre
// (nearest-exact), the rule the bilinear image resize and K follow; plain nearest sits half a pixel off.
torch::Tensor resize_nearest(const torch::Tensor& maps, int64_t height, int64_t width) {
  auto source = [](int64_t out, int64_t in) {
    return ((torch::arange(out, torch::kFloat64) + 0.5) * (static_cast<double>(in) / out))
        .floor()
        .clamp_max(in - 1)
        .to(torch::kLong);
  };
  return maps.index_select(1, source(height, maps.size(1))).index_select(2, source(width, maps.size(2)));
}

// ax, ay in [0, 1]: where the window sits between the image's left/top and right/bottom edges.
void zoom_view(ViewTensors& view, double z, double ax, double ay) {
  const int64_t H = view.image.size(1), W = view.image.size(2);
  const int64_t cw = std::max<int64_t>(1, std::lround(W / z)), ch = std::max<int64_t>(1, std::lround(H / z));
  const int64_t x0 = std::lround(ax * (W - cw)), y0 = std::lround(ay * (H - ch));
  const auto K = view.camera.K;
  auto [cropped, K_crop] = crop_with_K(view.image, K, x0, y0, cw, ch);
  std::tie(view.image, view.camera.K) = resize_with_K(cropped, K_crop, H, W);
  view.image = view.image.clamp(0, 1).contiguous();
  if (view.depth.defined() && view.depth.numel() > 0) {
    const auto maps = crop_with_K(torch::stack({view.depth, view.valid}), K, x0, y0, cw, ch).first;
    const auto resized = resize_nearest(maps, H, W);
    view.depth = resized[0].contiguous();
    view.valid = resized[1].contiguous();
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
  view.camera.K = mirror_K(view.camera.K, W);
  const auto M = torch::diag(torch::tensor({-1.0, 1.0, 1.0, 1.0}, view.camera.T_cw.options()));
  view.camera.T_cw = torch::matmul(torch::matmul(M, view.camera.T_cw), M);
}

}  // namespace

void augment_tuple(TupleSample& sample, const AugmentOptions& o, uint64_t seed) {
  if (!o.any()) return;
  // One stream per decision, so switching one option on leaves the others' draws for a tuple unchanged.
  enum Stream : uint64_t { kGamma, kGain, kContrast, kSaturation, kShuffle, kGray, kMirror, kZoom };
  auto stream = [seed](Stream s) { return std::mt19937_64(mix_seed(seed, s)); };
  Photometric p;
  auto r_gamma = stream(kGamma), r_gain = stream(kGain), r_contrast = stream(kContrast), r_sat = stream(kSaturation);
  p.gamma = log_uniform(o.gamma, r_gamma);
  p.gain = log_uniform(o.brightness, r_gain);
  p.contrast = log_uniform(o.contrast, r_contrast);
  p.saturation = log_uniform(o.saturation, r_sat);
  auto r_shuffle = stream(kShuffle), r_gray = stream(kGray), r_mirror = stream(kMirror), r_zoom = stream(kZoom);
  if (chance(o.channel_shuffle, r_shuffle)) std::shuffle(p.order.begin(), p.order.end(), r_shuffle);
  p.gray = chance(o.gray, r_gray);
  const bool mirror = chance(o.flip, r_mirror);
  std::vector<ViewTensors*> views = {&sample.context};
  for (auto& t : sample.targets) views.push_back(&t);
  std::uniform_real_distribution<double> u(0, 1);
  for (ViewTensors* v : views) {
    if (o.zoom > 0) {
      const double z = 1 + o.zoom * u(r_zoom);
      const double ax = u(r_zoom), ay = u(r_zoom);
      zoom_view(*v, z, ax, ay);
    }
    if (!p.identity()) v->image = apply_photometric(v->image, p);
    if (mirror) mirror_view(*v);
  }
}

}  // namespace isplat
