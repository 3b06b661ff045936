// The InfiniSplat model, end to end: supports from depth -> base Gaussians; image -> dual features;
// decoder (dense or implicit) -> 14-dim updates; composer -> metric Gaussians in the world frame.
#pragma once
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <torch/nn/module.h>
#include <torch/nn/pimpl.h>

#include "core/gaussians.h"
#include "decoder/composer.h"
#include "decoder/dense_head.h"
#include "decoder/implicit_decoder.h"
#include "encoder/dual_encoder.h"
#include "prior/depth_prior.h"
#include "sampler/base_gaussians.h"
#include "sampler/sampler.h"

namespace isplat {

class ConfigVisitor;

// The model's defaults are the recipe the lab's studies adopted (config_version 3, lab/README.md): the sampler,
// decoder and composer structs alone keep the paper release's; model_defaults in model/model_io.h restores older ones.
struct ModelOptions {
  ModelOptions();
  std::string variant = "rgb";  // rgb | lidar: which prior family the checkpoint was trained with
  PriorOptions prior;
  SamplerOptions sampler;
  EncoderOptions encoder;
  DecoderOptions decoder;
  ComposerOptions composer;
  void visit(ConfigVisitor& v);
};

struct Prediction {
  Gaussians gaussians;  // world frame, metres
  Supports supports;
  BaseGaussians base;
  torch::Tensor delta;                       // [N,14]
  std::map<std::string, double> timings_ms;  // sampler, encoder, decoder, composer
};

struct InfiniSplatImpl : torch::nn::Module {
  explicit InfiniSplatImpl(const ModelOptions& options);

  // image [3,H,W] sRGB; K [3,3]; T_cw [4,4]; depth/valid [H,W] from the prior. Differentiable in the
  // network weights (supports and base Gaussians are fixed functions of the prior).
  Prediction forward(const torch::Tensor& image, const torch::Tensor& K, const torch::Tensor& T_cw,
                     const torch::Tensor& depth, const torch::Tensor& valid, uint64_t seed = 0);
  // Inference: no autograd (the implicit decoder's chunks bound its memory).
  Prediction predict(const torch::Tensor& image, const torch::Tensor& K, const torch::Tensor& T_cw,
                     const torch::Tensor& depth, const torch::Tensor& valid, uint64_t seed = 0);
  // Updates [N,14] at supports uv of a W x H image from its encoder features: the implicit decoder, or
  // the dense head's map sampled at the supports (decoder.mode = dense).
  torch::Tensor decode(const EncoderFeatures& features, const torch::Tensor& uv, int64_t width, int64_t height);

  ModelOptions options;
  DualEncoder encoder{nullptr};
  ImplicitDecoder decoder{nullptr};
  DenseHead dense{nullptr};
};
TORCH_MODULE(InfiniSplat);

// Prior + model: the whole path from one photograph (and optional depth/prompts) to Gaussians.
class Pipeline {
 public:
  explicit Pipeline(const ModelOptions& options, const std::map<std::string, torch::Tensor>* embedded_prior = nullptr);
  // after_prior, when set, may change the prior's output before the model sees it (the stability suite
  // perturbs an image-only prior's depth this way).
  Prediction run(const PriorInput& input, const torch::Tensor& T_cw, bool train,
                 const std::function<void(PriorOutput&)>& after_prior = {});
  InfiniSplat& model() { return model_; }
  const DepthPrior& prior() const { return *prior_; }

 private:
  std::unique_ptr<DepthPrior> prior_;
  InfiniSplat model_;
};

}  // namespace isplat
