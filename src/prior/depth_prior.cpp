// The depth priors' options and factory (one file per prior: dataset_prior, learned_prior, torchscript_prior,
// sparse_prior; the prompt alignment in align_prompts.cpp, the floor fit in floor_scale.cpp).
#include "prior/depth_prior.h"

#include <torch/torch.h>

#include "core/config.h"
#include "core/error.h"
#include "core/log.h"
#include "geometry/camera_torch.h"
#include "prior/learned_depth.h"
#include "prior/prior_common.h"

namespace isplat {

void SparsePriorOptions::visit(ConfigVisitor& v) {
  v.field("prompts", prompts, "sparse depth prompts drawn from the source depth (paper: 1500)", Range::at_least(3));
  v.field("noise", noise, "multiplicative prompt noise sigma (Table 4 uses 0, 0.01, 0.03, 0.05)", Range::at_least(0));
  v.field("mono", mono,
          "monocular prior aligned to the prompts; dataset = the frame's own true depth (a diagnostic of a prior "
          "with the right shape, evaluations only)",
          {"learned", "torchscript", "dataset", "none"});
  v.field("mono_warp", mono_warp,
          "mono = dataset: warp that depth by exp(sigma f), f a smooth unit-variance random field (3 cells across the "
          "width, seeded per frame): a prior wrong in shape (0 = the right shape)",
          Range::between(0, 3));
  v.require("mono_warp", mono_warp == 0 || mono == "dataset", "needs prior.sparse.mono = dataset");
  v.field("densify", densify,
          "how prompts become dense depth: fit (the monocular prior aligned, then its residual field), image (the "
          "prompts alone, interpolated edge-aware in the image), blend (image, with the fit taken per region where "
          "held-out prompts show it cuts the error; the default, lab/2026-12-06-densify); checkpoints stored "
          "without the key keep fit",
          {"fit", "image", "blend"});
  v.field("color_range", color_range,
          "densify = image or blend: colour range (sRGB units) of the joint bilateral kernel; a prompt counts less "
          "for a pixel of another colour (1 chosen on the development scenes: 0.1 and 0.3 made textured surfaces "
          "bumpy, -1.5 and -0.4 dB; lab/2026-12-06-densify)",
          Range::between(0.01, 10));
  v.field("far", far,
          "pixels further than far_spacings from every prompt (where a sensor returned nothing): keep the "
          "densified depth, drop it (invalid: no supports, as dataset depth there), or keep it only behind the "
          "farthest supported depth nearby (it cannot occlude what the prompts support)",
          {"keep", "drop", "behind"});
  v.field("far_spacings", far_spacings,
          "the far rule's distance to the nearest prompt, in mean prompt spacings "
          "sqrt(H W / prompts)",
          Range::above(0));
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
  v.field("learned_sky_m", learned_sky_m,
          "learned depth at or beyond this many metres is sky and marked invalid (no supports); 0 = never. For nets "
          "trained with loss.depth_sky, set it below loss.depth_sky_m",
          Range::at_least(0));
  v.field("learned_flip_average", learned_flip_average,
          "learned prior: also predict from the left-right mirrored photo (with its mirrored intrinsics) and take the "
          "geometric mean of the two depths, pixel by pixel; twice the prior's time");
  v.field("camera_height_m", camera_height_m,
          "learned and torchscript priors: set the metric scale from the camera's height above the ground (find "
          "the floor in the lower image, rescale so it lies this many metres below); frames without a visible floor "
          "keep the net's scale. 1.6 suits photos taken standing; 0 = off",
          Range::at_least(0));
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
  if (o.type == "dataset") return priors::make_dataset_prior(o);
  if (o.type == "learned") return priors::make_learned_prior(o, embedded);
  if (o.type == "torchscript") return priors::make_torchscript_prior(o);
  if (o.type == "sparse") return priors::make_sparse_prior(o, embedded);
  fail("prior.type: unknown '", o.type, "'");
}

}  // namespace isplat
