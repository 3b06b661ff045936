// Checkpoint, lift and identity methods.
#include "eval/methods.h"

#include <torch/torch.h>

#include <chrono>
#include <filesystem>
#include <functional>

#include "core/error.h"
#include "core/progress.h"
#include "core/runtime.h"
#include "core/tensor_memory.h"
#include "data/perturb.h"
#include "decoder/composer.h"
#include "geometry/color.h"
#include "io/folder_lock.h"
#include "model/model_io.h"
#include "render/prune.h"
#include "render/render.h"
#include "sampler/base_gaussians.h"

namespace isplat {
namespace {

using Clock = std::chrono::steady_clock;

// The tensor memory a prediction and its render need: the peak of live CPU tensor bytes above those live at the start.
class WorkMemory {
 public:
  WorkMemory() : live0_(live_tensor_bytes()) { reset_tensor_peak(); }
  double mb() const {
    return tensor_memory_counted() ? double(peak_tensor_bytes() - live0_) / (1 << 20)
                                   : std::numeric_limits<double>::quiet_NaN();
  }

 private:
  int64_t live0_;
};

class ModelMethod final : public Method {
 public:
  ModelMethod(const MethodOptions& o, const RenderOptions& r, const RenderMaps& maps)
      : options_(o), render_(r), maps_(maps), precision_(method_precision(o)) {
    ISPLAT_CHECK(!o.checkpoint.empty(), "method '", o.name, "': type model needs a checkpoint (methods[].checkpoint)");
    pipeline_ = load_pipeline(o.checkpoint, o.overrides);
    ISPLAT_CHECK(
        o.sweep.budget.empty() || pipeline_->model()->options.sampler.has_budget(), "method '", o.name,
        "': budgets sweep the support budget, but ", o.checkpoint,
        " samples in pixel mode, one support per pixel, which has none; add the overrides sampler.mode=area and "
        "sampler.edge_supports=true to sweep area sampling's budget");
  }
  MethodOutput predict(const ViewTensors& src, const Camera& target, uint64_t seed, const torch::Tensor& prompts,
                       const AlignScene& align) override {
    torch::NoGradGuard g;
    const PrecisionScope precision(precision_);
    const bool peak = reset_peak_memory();
    const WorkMemory work;
    PriorInput in{src.image, src.camera.K, src.depth, src.valid, prompts, seed, src.true_depth};
    auto t0 = Clock::now();
    // Depth perturbations reach a dataset or sparse prior through the source depth (eval/evaluator); an
    // image-only prior ignores that depth, so its own output is perturbed instead.
    const std::string& type = pipeline_->model()->options.prior.type;
    std::function<void(PriorOutput&)> after_prior;
    MethodOutput out;
    if (options_.perturb.any_depth() && type != "dataset" && type != "sparse")
      after_prior = [&](PriorOutput& po) {
        const PerturbedDepth d = perturb_depth(po.depth, po.valid, options_.perturb, seed, src.image, po.K);
        po.depth = d.depth, po.valid = d.valid;
      };
    if (type == "sparse") {  // the densified depth and the prompts' pixels, for the evaluator's densification scores
      after_prior = [&](PriorOutput& po) { out.densified = (po.depth * (po.valid > 0)).clone(); };
      const SparsePriorOptions& sp = pipeline_->model()->options.prior.sparse;
      const torch::Tensor used =
          prompts.defined() ? prompts
                            : draw_prompts(src.depth, src.valid.defined() ? src.valid : (src.depth > 0), sp.prompts,
                                           sp.noise, seed);  // the draw the prior makes (prior/sparse_prior.cpp)
      out.prompt_pixels = torch::floor(used.narrow(1, 0, 2)).to(torch::kLong);
    }
    const Prediction p = pipeline_->run(in, src.camera.T_cw, false, after_prior);
    out.stage_ms = p.timings_ms;
    out.decoded = p.gaussians.count();
    const auto tp = Clock::now();
    const PruneResult pr = prune_gaussians(p.gaussians, src.camera, options_.prune, render_);
    if (options_.prune.enabled) out.stage_ms["prune"] = ms_since(tp), out.prune_counts = prune_counts(pr);
    out.infer_ms = ms_since(t0);
    Gaussians scene = pr.kept;
    if (align) out.scale = align(scene), out.aligned = true;
    t0 = Clock::now();
    const RenderOutput r = render(scene, target, render_, maps_);
    out.render_ms = ms_since(t0);
    out.linear_rgb = pipeline_->model()->options.composer.linear_rgb;
    out.image = rendered_srgb(r.rgb, out.linear_rgb);
    out.scene = scene;
    out.gaussians = pr.kept.count();
    out.alpha = r.alpha, out.depth = r.depth, out.normal = r.normal, out.median_depth = r.median_depth;
    if (peak) out.peak_mb = peak_memory_mb();
    out.work_mb = work.mb();
    return out;
  }
  std::string describe() const override { return "checkpoint " + options_.checkpoint; }
  bool needs_source_depth(bool have_prompts) const override {
    const std::string& type = pipeline_->model()->options.prior.type;
    return type == "dataset" || (type == "sparse" && !have_prompts);
  }

 private:
  MethodOptions options_;
  RenderOptions render_;
  RenderMaps maps_;
  Precision precision_;
  std::unique_ptr<Pipeline> pipeline_;
};

// The source image lifted on its (dataset) depth: one base Gaussian per pixel, no learning.
class LiftMethod final : public Method {
 public:
  LiftMethod(const RenderOptions& r, const RenderMaps& maps) : render_(r), maps_(maps) {}
  MethodOutput predict(const ViewTensors& src, const Camera& target, uint64_t, const torch::Tensor&,
                       const AlignScene& align) override {
    torch::NoGradGuard g;
    const WorkMemory work;
    auto t0 = Clock::now();
    SamplerOptions px;
    px.mode = "pixel";
    const Supports s = sample_supports(src.depth, src.valid, src.camera.K, src.image, px);
    const BaseGaussians base = make_base_gaussians(s);
    Gaussians gs =
        compose(base, torch::zeros({s.count(), kDeltaDim}), src.camera.K, src.camera.T_cw, ComposerOptions{});
    MethodOutput out;
    if (align) out.scale = align(gs), out.aligned = true;
    out.infer_ms = ms_since(t0);
    t0 = Clock::now();
    const RenderOutput r = render(gs, target, render_, maps_);
    out.render_ms = ms_since(t0);
    out.image = rendered_srgb(r.rgb, true);
    out.scene = gs;
    out.gaussians = out.decoded = gs.count();
    out.alpha = r.alpha, out.depth = r.depth, out.normal = r.normal, out.median_depth = r.median_depth;
    out.work_mb = work.mb();
    return out;
  }
  std::string describe() const override { return "lift: one base Gaussian per source pixel on the dataset depth"; }
  bool needs_source_depth(bool) const override { return true; }

 private:
  RenderOptions render_;
  RenderMaps maps_;
};

class IdentityMethod final : public Method {
 public:
  MethodOutput predict(const ViewTensors& src, const Camera& target, uint64_t, const torch::Tensor&,
                       const AlignScene&) override {  // nothing to scale: the image is copied
    ISPLAT_CHECK(src.image.size(1) == target.height && src.image.size(2) == target.width,
                 "identity: source and target sizes differ");
    MethodOutput out;
    out.image = src.image.clone();
    return out;
  }
  std::string describe() const override { return "identity: the source image as the target view"; }
};

}  // namespace

torch::Tensor rendered_srgb(const torch::Tensor& rgb, bool linear) {
  auto c = torch::clamp(rgb, 0.0, 1.0);
  return linear ? torch::clamp(linear_to_srgb(c), 0.0, 1.0) : c;
}

void require_finished_run(const std::string& method, const std::string& checkpoint) {
  const std::filesystem::path folder = std::filesystem::path(checkpoint).parent_path();
  if (folder.filename() != "checkpoints") return;  // a checkpoint outside a run folder
  const std::string holder = folder_lock_holder(folder.parent_path().string());
  ISPLAT_CHECK(holder.empty(), "method '", method, "': ", checkpoint, " belongs to a run that is still training (",
               folder.parent_path().string(), " is locked by pid ", holder,
               "); score it once the run has finished, or copy the checkpoint elsewhere to score it as it is");
}

std::unique_ptr<Method> make_method(const MethodOptions& o, const RenderOptions& r, const RenderMaps& maps) {
  if (o.type == "model") return std::make_unique<ModelMethod>(o, r, maps);
  if (o.type == "lift") return std::make_unique<LiftMethod>(r, maps);
  if (o.type == "identity") return std::make_unique<IdentityMethod>();
  fail("method '", o.name, "': unknown type '", o.type, "'");
}

}  // namespace isplat
