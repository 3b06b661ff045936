// Dual-branch encoder with ablation switches and optional DINOv3 weights.
#include "encoder/dual_encoder.h"

#include <torch/torch.h>

#include "core/config.h"
#include "core/error.h"
#include "core/log.h"
#include "core/weights.h"
#include "geometry/camera_torch.h"
#include "nets/feature_net.h"
#include "nets/imagenet.h"

namespace isplat {
namespace {
// SqueezeNet-1.1 `features` after fire9 (layer 12): 512 channels at stride 16, the ViT's patch grid.
constexpr int kSqueezeTap = 12;
}  // namespace

void EncoderOptions::visit(ConfigVisitor& v) {
  v.field("dino", dino, "use the ViT (DINO) branch; false = the 'w/o DINO' ablation");
  v.field("cnn", cnn, "use the CNN branch; false = the 'w/o CNN' ablation");
  v.field("semantic", semantic,
          "semantic branch: vit (DINO-style ViT, trained or from encoder.vit.weights) | squeeze (frozen pretrained "
          "SqueezeNet-1.1 ImageNet features at stride 16 and a trained 1x1 projection to encoder.vit's width, so the "
          "decoder costs the same; the option where no DINO checkpoint exists)",
          {"vit", "squeeze"});
  v.field("semantic_backbone", semantic_backbone,
          "semantic = squeeze: torchvision SqueezeNet-1.1 `features` safetensors (ships with the project)");
  v.section("vit", "the DINOv3-style ViT branch", vit);
  v.section("cnn_branch", "the CNN branch", cnn_options);
}

DualEncoderImpl::DualEncoderImpl(const EncoderOptions& o) {
  ISPLAT_CHECK(o.dino || o.cnn, "encoder: encoder.dino and encoder.cnn cannot both be false");
  if (o.dino && o.semantic == "squeeze") {
    const std::string backbone = find_weights_file(o.semantic_backbone);
    ISPLAT_CHECK(!backbone.empty(), "encoder: encoder.semantic = squeeze needs encoder.semantic_backbone '",
                 o.semantic_backbone, "': not found; ", missing_weights_hint());
    squeeze = std::make_shared<const FeatureNet>("squeezenet1_1", std::vector<int>{kSqueezeTap}, backbone);
    squeeze_proj = register_module(
        "squeeze_proj", torch::nn::Conv2d(torch::nn::Conv2dOptions(squeeze->tap_channels()[0], o.vit.dim(), 1)));
    log_info("encoder: semantic branch = frozen pretrained SqueezeNet-1.1 features from ", o.semantic_backbone,
             ", projected to ", o.vit.dim(), " channels (no ViT)");
  } else if (o.dino) {
    vit = register_module("vit", DinoViT(o.vit));
    if (!o.initial_weights_matter) {
      // Loaded from a trained checkpoint by the caller.
    } else if (o.vit.weights.empty()) {
      log_info("encoder: ViT-", o.vit.size,
               " starts from random weights (no DINOv3 checkpoint given in "
               "encoder.vit.weights; none ships with this project)");
    } else {
      const std::string path = find_weights_file(o.vit.weights);
      ISPLAT_CHECK(!path.empty(), "encoder: encoder.vit.weights '", o.vit.weights, "': not found; ",
                   missing_weights_hint(), " (DINOv3 comes from its publisher, not from that command)");
      load_dinov3_safetensors(vit, path);
      log_info("encoder: loaded DINOv3 weights from ", path);
    }
  }
  if (o.cnn) cnn = register_module("cnn", CNNEncoder(o.cnn_options));
}

int64_t DualEncoderImpl::dino_dim() const {
  return vit ? vit->dim() : squeeze_proj ? squeeze_proj->options.out_channels() : 0;
}

EncoderFeatures DualEncoderImpl::forward(const torch::Tensor& image) {
  ISPLAT_CHECK(image.dim() == 4 && image.size(1) == 3, "encoder: image must be [B, 3, H, W], got ", image.sizes());
  ISPLAT_CHECK(image.size(2) >= 16 && image.size(3) >= 16, "encoder: image ", image.size(3), "x", image.size(2),
               " is smaller than one 16x16 ViT patch");
  const int64_t H = std::max<int64_t>(16, (image.size(2) + 8) / 16 * 16),
                W = std::max<int64_t>(16, (image.size(3) + 8) / 16 * 16);
  torch::Tensor x = image;
  if (H != image.size(2) || W != image.size(3)) x = resize_bilinear(image, H, W);
  EncoderFeatures f;
  if (vit) f.dino = vit->forward(x);
  if (squeeze) {
    torch::Tensor frozen_features;
    {
      torch::NoGradGuard frozen;  // pretrained and not trained; gradients stop at its output
      // Unit length over channels, times sqrt(C): entries of unit RMS, like the ViT's layer-normed tokens.
      frozen_features = normalize_channels(squeeze->forward(imagenet_normalize(x))[0]) *
                        std::sqrt(static_cast<double>(squeeze_proj->weight.size(1)));
    }
    f.dino = squeeze_proj->forward(frozen_features);
  }
  if (cnn) f.cnn = cnn->forward(x);
  return f;
}

}  // namespace isplat
