// Depth prior implementations and the sparse-prompt alignment.
#include "prior/depth_prior.h"

#include <torch/script.h>
#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <numeric>
#include <random>

#include <Eigen/Eigenvalues>

#include "core/config.h"
#include "core/error.h"
#include "core/log.h"
#include "geometry/bilinear.h"
#include "geometry/camera_torch.h"
#include "io/checkpoint.h"
#include "io/safetensors.h"
#include "prior/learned_depth.h"

namespace isplat {

void SparsePriorOptions::visit(ConfigVisitor& v) {
  v.field("prompts", prompts, "sparse depth prompts drawn from the source depth (paper: 1500)", Range::at_least(3));
  v.field("noise", noise, "multiplicative prompt noise sigma (Table 4 uses 0, 0.01, 0.03, 0.05)", Range::at_least(0));
  v.field("mono", mono, "monocular prior aligned to the prompts", {"learned", "torchscript", "none"});
  v.field("bandwidth", bandwidth, "residual scale field: coarsest kernel width, fraction of the image diagonal",
          Range::above(0));
  v.field("finest", finest,
          "residual scale field: finest kernel width (fraction of the diagonal); levels halve from bandwidth down "
          "to it, each fitting what the coarser left (= bandwidth: one smooth level)",
          Range::above(0));
  v.field("cross_validate", cross_validate,
          "stop refining at the level after which held-out prompts (5-fold) stop improving, so noisy prompts keep "
          "a smoother fit");
  v.field("depth_range", depth_range,
          "edge-aware residual field: > 0 weighs each prompt also by exp(-(log-depth gap)^2 / (2 range^2)) between "
          "the aligned monocular depth at the prompt and at the pixel, so a prompt corrects its own surface and not "
          "the one across a depth edge (0 = off; 0.1 chosen on the development scenes, "
          "docs/results/2026-11-25-lidar-fit.md)",
          Range::at_least(0));
}

void PriorOptions::visit(ConfigVisitor& v) {
  v.field("type", type,
          "depth prior: the tuple's own depth (oracle), sparse prompts (LiDAR variant), a TorchScript "
          "model, or the project's learned net (RGB-only default)",
          {"dataset", "sparse", "torchscript", "learned"});
  v.field("hfov_deg", hfov_deg, "horizontal field of view assumed when an image comes without intrinsics",
          Range::between(1, 179));
  v.field("torchscript", torchscript, "traced depth model: input [1,3,H,W] in [0,1], output metric depth [1,1,H,W]");
  v.field("learned_weights", learned_weights,
          "safetensors of the learned depth net (train it with task: depth); "
          "empty = untrained, which the log says");
  v.field("learned_width", learned_width, "channel width of the learned depth net", Range::between(4, 1024));
  v.field("learned_arch", learned_arch,
          "learned depth net: a U-Net from scratch, or a decoder on the frozen pretrained SqueezeNet-1.1 "
          "features (weights/)",
          {"unet", "squeeze"});
  v.field("learned_focal", learned_focal,
          "focal-normalized learned depth: predict for a canonical 60-degree camera, scale by the image's fx/W");
  v.field("learned_backbone", learned_backbone, "squeeze arch: SqueezeNet-1.1 features (torchvision names)");
  v.field("learned_backbone_lr", learned_backbone_lr,
          "task: depth, squeeze arch: > 0 fine-tunes the pretrained encoder at this multiple of optim.lr, and the "
          "net's weights file then carries it (loading detects that, so scoring needs no option); 0 = frozen",
          Range::at_least(0));
  v.require("learned_backbone_lr", learned_backbone_lr == 0 || learned_arch == "squeeze",
            "fine-tunes the pretrained encoder, which only prior.learned_arch = squeeze has");
  v.field("learned_sky_m", learned_sky_m,
          "learned depth at or beyond this many metres is sky and marked invalid (no supports); 0 = never. For nets "
          "trained with loss.depth_sky, set it below loss.depth_sky_m",
          Range::at_least(0));
  v.field("learned_flip_average", learned_flip_average,
          "learned prior: also predict from the left-right mirrored photo (with its mirrored intrinsics) and take the "
          "geometric mean of the two depths, pixel by pixel; twice the prior's time");
  v.field("learned_input_width", learned_input_width,
          "learned prior: run the net on the photo resized to this many pixels wide (the height keeps the aspect; K "
          "is scaled with it, so a focal-normalized net reads the same metric scale), and bring the log depth back "
          "to the photo's size. A net sees objects at the pixel size it was trained at (e.g. the tuples' width); "
          "0 = the photo's own size",
          Range::between(0, 8192));
  v.require("learned_input_width", learned_input_width == 0 || learned_input_width >= 16,
            "is 0 (the photo's own size) or at least 16 pixels");
  v.field("camera_height_m", camera_height_m,
          "learned and torchscript priors: set the metric scale from the camera's height above the ground (find "
          "the floor in the lower image, rescale so it lies this many metres below); frames without a visible floor "
          "keep the net's scale. 1.6 suits photos taken standing; 0 = off",
          Range::at_least(0));
  v.field("floor_rule", floor_rule,
          "camera_height_m: which horizontal plane is the floor. best: the best-supported one in the lower image; "
          "nearest: of up to three (each with at least a third of the best one's support), the one whose scale is "
          "nearest the net's own, so a table top is not taken for the floor",
          {"best", "nearest"});
  v.field("reference_scale", reference_scale,
          "diagnostic for learned and torchscript priors: scale each frame's depth so that its median ratio to the "
          "frame's own depth is 1 (an oracle metric scale with the model's shape; needs dataset depth, so "
          "evaluations only, never photographs)");
  v.require("reference_scale", !(reference_scale && camera_height_m > 0),
            "cannot be combined with prior.camera_height_m (both set the scale)");
  v.section("sparse", "the sparse-prompt (LiDAR) variant", sparse);
}

LearnedDepthOptions learned_depth_options(const PriorOptions& o) {
  return {o.learned_arch, o.learned_width, o.learned_focal, o.learned_backbone};
}

torch::Tensor estimate_K(int64_t width, int64_t height, double hfov_deg) {
  const Intrinsics k =
      Intrinsics::from_hfov(hfov_deg * M_PI / 180.0, static_cast<int>(width), static_cast<int>(height));
  return make_K(k.fx, k.fy, k.cx, k.cy, torch::kFloat32);
}

namespace {

torch::Tensor intrinsics_for(const PriorInput& in, double hfov) {
  return in.K.defined() ? in.K.to(torch::kFloat32) : estimate_K(in.image.size(2), in.image.size(1), hfov);
}

void check_image(const PriorInput& in) {
  ISPLAT_CHECK(in.image.defined() && in.image.dim() == 3 && in.image.size(0) == 3,
               "depth prior: image must be [3, H, W], got ",
               in.image.defined() ? in.image.sizes() : torch::IntArrayRef{});
}

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

PriorOutput finish(torch::Tensor depth, torch::Tensor K) {
  depth = depth.to(torch::kFloat32);
  auto valid = (torch::isfinite(depth) & (depth > 0)).to(torch::kFloat32);
  return {torch::where(valid > 0, depth, torch::zeros_like(depth)), K, valid};
}

// The median of reference / depth over the pixels valid in both; 0 when none is.
double reference_ratio(const torch::Tensor& depth, const torch::Tensor& valid, const torch::Tensor& reference,
                       const torch::Tensor& reference_valid) {
  auto ref = reference.to(torch::kFloat32);
  auto both = (valid > 0) & torch::isfinite(ref) & (ref > 0);
  if (reference_valid.defined()) both = both & (reference_valid > 0);
  if (!both.any().item<bool>()) return 0.0;
  return (ref.masked_select(both) / depth.masked_select(both)).median().item<double>();
}

// Monocular priors: metric scale from the camera's height when asked and a floor is visible, or (a diagnostic)
// from the frame's own depth.
PriorOutput finish_monocular(torch::Tensor depth, torch::Tensor K, const PriorOptions& o, const PriorInput& in) {
  PriorOutput out = finish(std::move(depth), std::move(K));
  double scale = 0.0;
  if (o.camera_height_m > 0) {
    scale = floor_height_scale(out.depth, out.valid, out.K, o.camera_height_m, o.floor_rule);
    out.floor_scaled = scale > 0;
  } else if (o.reference_scale) {
    ISPLAT_CHECK(in.depth.defined(),
                 "prior.reference_scale needs the frame's own depth, and this input has none (it is a diagnostic for "
                 "datasets with depth)");
    scale = reference_ratio(out.depth, out.valid, in.depth, in.valid);
  }
  if (scale > 0) out.depth = out.depth * static_cast<float>(scale);
  return out;
}

class DatasetPrior final : public DepthPrior {
 public:
  explicit DatasetPrior(const PriorOptions& o) : o_(o) {}
  PriorOutput predict(const PriorInput& in) override {
    check_image(in);
    ISPLAT_CHECK(in.depth.defined(),
                 "prior.type = dataset needs the frame's depth, and this input has none; use "
                 "prior.type = learned | torchscript | sparse");
    auto d = in.depth.to(torch::kFloat32);
    if (in.valid.defined()) d = torch::where(in.valid > 0, d, torch::zeros_like(d));
    return finish(d, intrinsics_for(in, o_.hfov_deg));
  }
  std::string describe() const override { return "dataset depth (oracle)"; }

 private:
  PriorOptions o_;
};

class LearnedPrior final : public DepthPrior {
 public:
  explicit LearnedPrior(const PriorOptions& o, const std::map<std::string, torch::Tensor>* embedded = nullptr)
      : o_(o), net_(learned_depth_options(o)) {
    const auto load = [&](const std::map<std::string, torch::Tensor>& tensors, const std::string& prefix,
                          const std::string& what) {
      if (has_tuned_backbone(tensors, prefix)) net_->tune_backbone();  // a fine-tuned encoder ships with the weights
      load_named_tensors(*net_, tensors, prefix, what);
    };
    if (embedded && embedded->count("prior/stem.weight")) {
      load(*embedded, "prior/", "checkpoint: embedded depth-net weights do not fit the net");
      source_ = "weights embedded in the checkpoint";
    } else if (o.learned_weights.empty()) {
      log_warn(
          "depth prior: the learned depth net has no weights (prior.learned_weights is empty); its depth is "
          "untrained. Train it with a `task: depth` config or pass prior.torchscript.");
    } else {
      load(read_safetensors(o.learned_weights).tensors, "",
           o.learned_weights + ": does not fit the learned depth net (prior.learned_width must match)");
      source_ = o.learned_weights;
    }
    net_->eval();
  }
  PriorOutput predict(const PriorInput& in) override {
    check_image(in);
    torch::NoGradGuard g;
    const torch::Tensor K = intrinsics_for(in, o_.hfov_deg);
    const int64_t H = in.image.size(1), W = in.image.size(2);
    torch::Tensor net_image = in.image.to(torch::kFloat32), net_K = K.to(torch::kFloat32);
    const bool resized = o_.learned_input_width > 0 && o_.learned_input_width != W;
    if (resized) {
      const int64_t w = o_.learned_input_width,
                    h = std::max<int64_t>(16, std::llround(static_cast<double>(H) * w / static_cast<double>(W)));
      std::tie(net_image, net_K) = resize_with_K(net_image, net_K, h, w);
    }
    const torch::Tensor image = net_image.unsqueeze(0), K1 = net_K.unsqueeze(0);
    torch::Tensor log_d = net_->forward_log(image, K1);
    if (o_.learned_flip_average) {
      // The mirrored photo is another view of the same scene. Averaging in log depth keeps the result metric and
      // cancels errors the net makes differently on the two.
      const torch::Tensor Km = mirror_K(K1, image.size(3));
      log_d = 0.5 * (log_d + net_->forward_log(image.flip({3}), Km).flip({3}));
    }
    if (resized) log_d = resize_bilinear(log_d, H, W);
    torch::Tensor d = torch::exp(log_d)[0][0];
    if (o_.learned_sky_m > 0) d = torch::where(d >= o_.learned_sky_m, torch::zeros_like(d), d);  // sky: invalid
    return finish_monocular(d, K, o_, in);
  }
  std::string describe() const override {
    const std::string kind = cat("learned depth net (", o_.learned_arch, o_.learned_focal ? ", focal-normalized" : "",
                                 o_.learned_flip_average ? ", flip-averaged" : "",
                                 o_.learned_input_width > 0 ? cat(", run ", o_.learned_input_width, " px wide") : "");
    return source_.empty() ? kind + ", untrained)" : kind + ", " + source_ + ")";
  }
  const torch::nn::Module* embeddable_weights() const override { return source_.empty() ? nullptr : net_.get(); }

 private:
  PriorOptions o_;
  LearnedDepthNet net_;
  std::string source_;
};

class TorchScriptPrior final : public DepthPrior {
 public:
  explicit TorchScriptPrior(const PriorOptions& o) : o_(o) {
    ISPLAT_CHECK(!o.torchscript.empty(), "prior.type = torchscript needs prior.torchscript (path of a traced model)");
    ISPLAT_CHECK(std::filesystem::exists(o.torchscript), o.torchscript, ": no such file (prior.torchscript)");
    try {
      module_ = torch::jit::load(o.torchscript);
    } catch (const std::exception& e) {
      fail(o.torchscript, ": cannot load TorchScript model: ", e.what());
    }
    module_.eval();
  }
  PriorOutput predict(const PriorInput& in) override {
    check_image(in);
    torch::NoGradGuard g;
    const int64_t H = in.image.size(1), W = in.image.size(2);
    torch::jit::IValue out;
    try {
      out = module_.forward({in.image.unsqueeze(0).to(torch::kFloat32)});
    } catch (const std::exception& e) {
      fail(o_.torchscript, ": the depth model failed on a [1,3,", H, ",", W, "] input: ", e.what());
    }
    ISPLAT_CHECK(out.isTensor(), o_.torchscript, ": the depth model must return one tensor (metric depth [1,1,H,W])");
    auto d = out.toTensor();
    // Contract: [1,1,H,W]; [1,H,W] and [H,W] are accepted as the same thing.
    if (d.dim() == 4 && d.size(0) == 1 && d.size(1) == 1)
      d = d[0][0];
    else if (d.dim() == 3 && d.size(0) == 1)
      d = d[0];
    if (d.dim() != 2 || d.size(0) != H || d.size(1) != W)
      fail(o_.torchscript, ": depth model returned shape ", out.toTensor().sizes(), ", expected [1, 1, ", H, ", ", W,
           "] (metric depth at the input size)");
    return finish_monocular(d, intrinsics_for(in, o_.hfov_deg), o_, in);
  }
  std::string describe() const override { return "TorchScript depth model (" + o_.torchscript + ")"; }

 private:
  PriorOptions o_;
  torch::jit::Module module_;
};

class SparsePrior final : public DepthPrior {
 public:
  explicit SparsePrior(const PriorOptions& o, const std::map<std::string, torch::Tensor>* embedded) : o_(o) {
    ISPLAT_CHECK(o.sparse.finest <= o.sparse.bandwidth, "prior.sparse.finest (", o.sparse.finest,
                 ") must not exceed prior.sparse.bandwidth (", o.sparse.bandwidth, ")");
    // Below 1e-3 the range kernel's 1/(2 range^2) overflows to inf and 0 * inf poisons the fit with NaN.
    ISPLAT_CHECK(o.sparse.depth_range == 0 || o.sparse.depth_range >= 1e-3, "prior.sparse.depth_range (",
                 o.sparse.depth_range, ") must be 0 (off) or at least 0.001");
    if (o.sparse.mono == "learned") {
      mono_ = std::make_unique<LearnedPrior>(o, embedded);
    } else if (o.sparse.mono == "torchscript") {
      mono_ = std::make_unique<TorchScriptPrior>(o);
    }
  }
  PriorOutput predict(const PriorInput& in) override {
    check_image(in);
    torch::NoGradGuard g;
    torch::Tensor prompts = in.prompts;
    if (!prompts.defined()) {
      ISPLAT_CHECK(in.depth.defined(), "prior.type = sparse needs prompts or the frame's depth to draw them from");
      prompts = draw_prompts(in.depth, in.valid.defined() ? in.valid : (in.depth > 0), o_.sparse.prompts,
                             o_.sparse.noise, in.seed);
    }
    ISPLAT_CHECK(prompts.dim() == 2 && prompts.size(1) == 3 && prompts.size(0) >= 3,
                 "sparse prior: prompts must be [P>=3, 3] (u, v, z), got ", prompts.sizes());
    const int64_t H = in.image.size(1), W = in.image.size(2);
    torch::Tensor mono = mono_ ? mono_->predict(in).depth : torch::ones({H, W});
    return finish(align_to_prompts(mono, prompts, o_.sparse), intrinsics_for(in, o_.hfov_deg));
  }
  std::string describe() const override {
    return cat("sparse prompts (", o_.sparse.prompts, ", noise ", o_.sparse.noise, ", residual field ",
               o_.sparse.bandwidth, " -> ", o_.sparse.finest, o_.sparse.cross_validate ? " cross-validated" : "",
               ") aligning ", mono_ ? mono_->describe() : std::string("a constant"));
  }
  const torch::nn::Module* embeddable_weights() const override { return mono_ ? mono_->embeddable_weights() : nullptr; }

 private:
  PriorOptions o_;
  std::unique_ptr<DepthPrior> mono_;
};

}  // namespace

double floor_height_scale(const torch::Tensor& depth, const torch::Tensor& valid, const torch::Tensor& K,
                          double height_m, const std::string& rule) {
  ISPLAT_CHECK(height_m > 0, "floor_height_scale: the camera height must be positive, got ", height_m);
  ISPLAT_CHECK(rule == "best" || rule == "nearest", "floor_height_scale: rule must be best or nearest, got '", rule,
               "'");
  ISPLAT_CHECK(depth.dim() == 2 && K.dim() == 2 && K.size(0) == 3 && K.size(1) == 3,
               "floor_height_scale: depth must be [H,W] and K [3,3], got ", depth.sizes(), " and ", K.sizes());
  auto d = depth.to(torch::kFloat32).contiguous();
  auto ok = usable_depth(d, valid.defined() ? valid : (d > 0)).contiguous();
  auto k = K.to(torch::kFloat64).contiguous();
  const double* kp = k.data_ptr<double>();
  const double fx = kp[0], fy = kp[4], cx = kp[2], cy = kp[5];
  const int64_t H = d.size(0), W = d.size(1), top = H / 2;
  // About 4000 samples from the lower half, where the ground of a photo taken standing shows.
  const int64_t stride =
      std::max<int64_t>(1, static_cast<int64_t>(std::sqrt(static_cast<double>((H - top) * W) / 4000.0)));
  const float* dp = d.data_ptr<float>();
  const bool* okp = ok.data_ptr<bool>();
  std::vector<Eigen::Vector3d> pts;
  for (int64_t i = top; i < H; i += stride)
    for (int64_t j = 0; j < W; j += stride)
      if (okp[i * W + j]) {
        const double z = dp[i * W + j];
        pts.emplace_back((j + 0.5 - cx) / fx * z, (i + 0.5 - cy) / fy * z, z);
      }
  const auto n_pts = static_cast<int64_t>(pts.size());
  constexpr int64_t kMinPoints = 30;
  if (n_pts < kMinPoints) return 0.0;
  // Up is -y in the OpenCV camera frame; a floor's normal points up and the floor lies below (h > 0).
  const double min_up = std::cos(40.0 * M_PI / 180.0), tol = 0.02;  // tol: distance as a share of depth
  std::vector<char> active(static_cast<size_t>(n_pts), 1);          // points no earlier plane claimed
  auto inliers = [&](const Eigen::Vector3d& n, double h, double share, std::vector<int64_t>* out) {
    int64_t count = 0;
    for (int64_t p = 0; p < n_pts; ++p)
      if (active[p] && std::fabs(n.dot(pts[p]) + h) <= share * pts[p].z()) {
        ++count;
        if (out) out->push_back(p);
      }
    return count;
  };
  struct Plane {
    Eigen::Vector3d n;
    double h = 0;
    int64_t support = 0;
  };
  std::mt19937_64 rng(0x5EEDF100Full);
  // RANSAC over the active points, then weighted least-squares refits on the inliers: weights 1/z^2 make
  // residuals relative, as the depth's errors are, so far points near a wall's crease do not tilt the plane;
  // the second refit uses half the tolerance.
  auto fit_plane = [&]() {
    std::vector<int64_t> pool;
    for (int64_t p = 0; p < n_pts; ++p)
      if (active[p]) pool.push_back(p);
    Plane best;
    if (static_cast<int64_t>(pool.size()) < kMinPoints) return best;
    for (int iter = 0; iter < 256; ++iter) {
      const auto& a = pts[pool[rng() % pool.size()]];
      const auto& b = pts[pool[rng() % pool.size()]];
      const auto& c = pts[pool[rng() % pool.size()]];
      Eigen::Vector3d n = (b - a).cross(c - a);
      if (n.norm() < 1e-12) continue;
      n.normalize();
      if (n.y() > 0) n = -n;
      const double h = -n.dot(a);
      if (-n.y() < min_up || h <= 0) continue;
      const int64_t count = inliers(n, h, tol, nullptr);
      if (count > best.support) best = {n, h, count};
    }
    if (best.support == 0) return best;
    for (int round = 0; round < 2; ++round) {
      std::vector<int64_t> in;
      inliers(best.n, best.h, tol / (1 + round), &in);
      double wsum = 0;
      Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
      for (int64_t p : in) {
        const double w = 1.0 / (pts[p].z() * pts[p].z());
        centroid += w * pts[p], wsum += w;
      }
      centroid /= wsum;
      Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
      for (int64_t p : in) cov += (pts[p] - centroid) * (pts[p] - centroid).transpose() / (pts[p].z() * pts[p].z());
      Eigen::Vector3d refit = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvectors().col(0);
      if (refit.y() > 0) refit = -refit;
      const double refit_h = -refit.dot(centroid);
      if (-refit.y() < min_up || refit_h <= 0) break;  // degenerate refit: keep the plane so far
      best.n = refit, best.h = refit_h;
    }
    return best;
  };
  const int64_t min_support = std::max<int64_t>(kMinPoints, n_pts / 10);
  auto plausible = [&](const Plane& p) {
    const double scale = height_m / p.h;
    return p.support >= min_support && scale > 0.02 && scale < 50.0;  // beyond: not a floor at any scale
  };
  const Plane first = fit_plane();
  if (!plausible(first)) return 0.0;
  if (rule == "best") return height_m / first.h;
  // nearest: up to three horizontal planes, each fitted to the points the earlier ones left, with at least a
  // third of the first one's support; the floor is the one whose scale the net's own agrees with best, so a
  // table top is not taken for the floor when the net's depth already puts the floor lower.
  Plane chosen = first;
  Plane current = first;
  for (int k = 1; k < 3; ++k) {
    std::vector<int64_t> claimed;
    inliers(current.n, current.h, tol, &claimed);
    for (int64_t p : claimed) active[p] = 0;
    current = fit_plane();
    if (!plausible(current) || 3 * current.support < first.support) break;
    if (std::fabs(std::log(height_m / current.h)) < std::fabs(std::log(height_m / chosen.h))) chosen = current;
  }
  return height_m / chosen.h;
}

torch::Tensor draw_prompts(const torch::Tensor& depth, const torch::Tensor& valid, int64_t count, double noise,
                           uint64_t seed) {
  auto d = depth.to(torch::kFloat32).contiguous();
  auto ok = usable_depth(d, valid).contiguous();
  auto idx = torch::nonzero(ok.flatten()).squeeze(1);
  ISPLAT_CHECK(idx.numel() > 0, "sparse prior: the source depth has no valid pixel to draw prompts from");
  std::mt19937_64 rng(seed * 0x9E3779B97F4A7C15ull + 12345);
  std::normal_distribution<double> eps(0.0, 1.0);
  const int64_t W = d.size(1), n = std::min<int64_t>(count, idx.numel());
  auto out = torch::empty({n, 3});
  const int64_t* ip = idx.data_ptr<int64_t>();
  const float* dp = d.data_ptr<float>();
  float* op = out.data_ptr<float>();
  // Partial Fisher-Yates: n distinct pixels.
  std::vector<int64_t> pool(ip, ip + idx.numel());
  for (int64_t k = 0; k < n; ++k) {
    const int64_t r = k + static_cast<int64_t>(rng() % static_cast<uint64_t>(pool.size() - k));
    std::swap(pool[k], pool[r]);
    const int64_t p = pool[k];
    op[3 * k] = static_cast<float>(p % W + 0.5);
    op[3 * k + 1] = static_cast<float>(p / W + 0.5);
    op[3 * k + 2] = static_cast<float>(dp[p] * std::max(0.05, 1.0 + noise * eps(rng)));
  }
  return out;
}

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

std::unique_ptr<DepthPrior> make_depth_prior(const PriorOptions& o,
                                             const std::map<std::string, torch::Tensor>* embedded) {
  // A run trained on a monocular prior is often scored with dataset depth (an experiment's variant): the
  // height has nothing to scale there, so it is ignored, and said so.
  if ((o.camera_height_m > 0 || o.reference_scale) && (o.type == "dataset" || o.type == "sparse")) {
    log_warn(o.reference_scale ? "prior.reference_scale" : cat("prior.camera_height_m = ", o.camera_height_m),
             " is ignored: prior.type = ", o.type, " has metric depth of its own");
    PriorOptions metric = o;
    metric.camera_height_m = 0, metric.reference_scale = false;
    return make_depth_prior(metric, embedded);
  }
  if (o.type == "dataset") return std::make_unique<DatasetPrior>(o);
  if (o.type == "learned") return std::make_unique<LearnedPrior>(o, embedded);
  if (o.type == "torchscript") return std::make_unique<TorchScriptPrior>(o);
  if (o.type == "sparse") return std::make_unique<SparsePrior>(o, embedded);
  fail("prior.type: unknown '", o.type, "'");
}

}  // namespace isplat
