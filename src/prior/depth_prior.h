// Frozen depth priors behind one interface (DESIGN §3): the tuple's own depth, the sparse-prompt "LiDAR"
// variant, a user's TorchScript model, and the project's own small learned network.
#pragma once
#include <map>
#include <memory>
#include <string>

#include <torch/types.h>

namespace torch::nn {
class Module;
}

namespace isplat {

class ConfigVisitor;

struct SparsePriorOptions {
  int64_t prompts = 1500;         // paper: 1,500 LiDAR-like prompts
  double noise = 0.0;             // multiplicative noise sigma: z(1 + eps), eps ~ N(0, sigma^2)
  std::string mono = "learned";   // monocular prior aligned to the prompts: learned | torchscript | dataset | none
  double mono_warp = 0.0;         // mono = dataset: the frame's true depth warped by a smooth random field (sigma)
  std::string densify = "blend";  // fit (the prior aligned) | image (prompts only, image-guided) | blend
  double color_range = 1.0;       // image-guided interpolation: colour range of the joint bilateral kernel (sRGB)
  std::string far = "keep";       // pixels further than far_spacings from every prompt: keep | drop | behind
  double far_spacings = 2.0;      // ... in mean prompt spacings sqrt(H W / P)
  double bandwidth = 0.08;        // residual scale field: coarsest Gaussian kernel width, fraction of the diagonal
  double finest = 0.005;          // finest kernel width; levels halve from bandwidth down to it
  bool cross_validate = true;     // stop refining where held-out prompts stop improving (noisy prompts stay smooth)
  double depth_range = 0.1;       // > 0: a prompt's weight also falls with the log-depth gap to the pixel (edge-aware)
  void visit(ConfigVisitor& v);
};

struct PriorOptions {
  std::string type = "dataset";       // dataset | sparse | torchscript | learned
  double hfov_deg = 60.0;             // field of view assumed when no intrinsics are given
  std::string torchscript;            // path of a traced model: input [1,3,H,W] in [0,1] -> metric depth [1,1,H,W]
  std::string learned_weights;        // safetensors of the learned depth net (from `task: depth` training)
  int64_t learned_width = 32;         // channel width of the learned depth net
  std::string learned_arch = "unet";  // unet (from scratch) | squeeze (frozen pretrained SqueezeNet encoder)
  bool learned_focal = false;         // the learned net predicts focal-normalized depth
  double learned_sky_m = 0.0;         // predictions at or beyond this depth are sky: invalid (0 = none)
  bool learned_flip_average = false;  // also read the mirrored photo; average the two in log depth
  double camera_height_m = 0.0;       // monocular priors: rescale so the floor lies this far below (0 = off)
  bool reference_scale = false;       // diagnostic: monocular depth scaled to the frame's own depth (median)
  std::string learned_backbone = "squeezenet1_1_features.safetensors";  // a file name: the weights lookup
  SparsePriorOptions sparse;
  void visit(ConfigVisitor& v);
};

struct LearnedDepthOptions;
LearnedDepthOptions learned_depth_options(const PriorOptions& options);  // the learned net's part

struct PriorInput {
  torch::Tensor image;    // [3,H,W] sRGB in [0,1]
  torch::Tensor K;        // [3,3] or undefined (estimated from hfov_deg)
  torch::Tensor depth;    // [H,W] dataset depth (dataset prior; prompt source for sparse), may be undefined
  torch::Tensor valid;    // [H,W]
  torch::Tensor prompts;  // [P,3] (u, v, z) sparse prompts given directly (e.g. from COLMAP points), optional
  uint64_t seed = 0;      // prompt draw and noise
  torch::Tensor reference_depth = {};  // [H,W] the view's unperturbed depth (evaluation), optional: prior.sparse.mono =
                                       // dataset reads it (else `depth`)
};

struct PriorOutput {
  torch::Tensor depth;            // [H,W] planar metres, 0 where invalid
  torch::Tensor K;                // [3,3]
  torch::Tensor valid;            // [H,W] float 0/1
  bool floor_scaled = false;      // camera_height_m found a floor and set the metric scale from it
  torch::Tensor confidence = {};  // [H,W] in [0,1], the sparse prior's (densify_prompts); undefined for the others
};

class DepthPrior {
 public:
  virtual ~DepthPrior() = default;
  virtual PriorOutput predict(const PriorInput& input) = 0;  // frozen: no gradients
  virtual std::string describe() const = 0;
  // The trained network a checkpoint should carry as "prior/<name>" so it alone predicts from a photo;
  // null when the prior has no loaded weights (oracle depth, TorchScript, an untrained net).
  virtual const torch::nn::Module* embeddable_weights() const { return nullptr; }
};

// `embedded`: tensors "prior/<name>" carried by a checkpoint; when present they replace learned_weights,
// so a checkpoint is self-contained.
std::unique_ptr<DepthPrior> make_depth_prior(const PriorOptions& options,
                                             const std::map<std::string, torch::Tensor>* embedded = nullptr);

// Pinhole K for a W x H image with the given horizontal field of view.
torch::Tensor estimate_K(int64_t width, int64_t height, double hfov_deg);

// Metric scale from the camera's height above the ground (prior.camera_height_m): RANSAC finds the
// best-supported plane in the lower half of the back-projected depth whose normal is within 40 degrees of
// the camera's up axis and which lies below the camera; the result is the factor that puts that plane
// `height_m` below the camera. 0 when no such floor is found (then the depth keeps its own scale).
// depth, valid [H,W]; K [3,3]. Deterministic.
double floor_height_scale(const torch::Tensor& depth, const torch::Tensor& valid, const torch::Tensor& K,
                          double height_m);

// Sparse alignment (exposed for tests): mono depth [H,W] aligned to prompts [P,3] with a global
// scale/shift in inverse depth, then a residual log-scale field fitted coarse to fine (kernel widths halving
// from options.bandwidth to options.finest), each level fitting what the coarser ones left at the prompts.
// With options.cross_validate, the number of levels is the one that predicts held-out prompts best (5-fold);
// `levels_used` (optional) receives it. Deterministic.
torch::Tensor align_to_prompts(const torch::Tensor& mono_depth, const torch::Tensor& prompts,
                               const SparsePriorOptions& options, int64_t* levels_used = nullptr);
// The sparse prior's densification (prior.sparse.densify, far, far_spacings): depth from prompts [P,3] (u, v, z) on
// image [3,H,W], with mono [H,W] the monocular depth (unused, may be undefined, for densify = image).
//   fit:   align_to_prompts(mono, prompts);
//   image: log depth interpolated from the prompts alone, coarse to fine, edge-aware in the image's colour;
//   blend: image, with the fit blended in per region (tiles of the coarsest kernel width, smoothed over their
//          neighbours) by how much it cuts the prompts' 5-fold held-out |log error| (weight 0 where it does not).
// confidence = exp(-d^2/2) / (1 + e/0.1), d the distance to the nearest prompt in mean spacings, e the local held-out
// error; pixels with d > far_spacings are kept, dropped (depth 0), or kept only where no supported depth nearby is
// farther (behind). Clear errors for prompts that are not [P>=3, 3], outside the image, or not positive.
struct SparseDensity {
  torch::Tensor depth;         // [H,W] metres, 0 where left out
  torch::Tensor confidence;    // [H,W] in [0,1]; 0 where left out
  torch::Tensor distance;      // [H,W] distance to the nearest prompt, in mean prompt spacings
  torch::Tensor prior_weight;  // [H,W] the fit's share: 1 (fit), 0 (image), per region (blend)
  int64_t levels = 0;          // levels of the field the result is built on (the fit's for fit, else the image's)
};
SparseDensity densify_prompts(const torch::Tensor& image, const torch::Tensor& mono, const torch::Tensor& prompts,
                              const SparsePriorOptions& options);
// Draws `count` prompts (u, v, z) from valid depth, with multiplicative noise sigma (deterministic in seed).
torch::Tensor draw_prompts(const torch::Tensor& depth, const torch::Tensor& valid, int64_t count, double noise,
                           uint64_t seed);

}  // namespace isplat
