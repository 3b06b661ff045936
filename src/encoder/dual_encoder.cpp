// Dual-branch encoder with ablation switches and optional DINOv3 weights.
#include "encoder/dual_encoder.h"

#include <torch/torch.h>

#include "core/config.h"
#include "core/error.h"
#include "core/log.h"
#include "geometry/camera_torch.h"

namespace isplat {

void EncoderOptions::visit(ConfigVisitor& v) {
  v.field("dino", dino, "use the ViT (DINO) branch; false = the 'w/o DINO' ablation");
  v.field("cnn", cnn, "use the CNN branch; false = the 'w/o CNN' ablation");
  v.section("vit", "the DINOv3-style ViT branch", vit);
  v.section("cnn_branch", "the CNN branch", cnn_options);
}

DualEncoderImpl::DualEncoderImpl(const EncoderOptions& o) {
  ISPLAT_CHECK(o.dino || o.cnn, "encoder: encoder.dino and encoder.cnn cannot both be false");
  if (o.dino) {
    vit = register_module("vit", DinoViT(o.vit));
    if (!o.initial_weights_matter) {
      // Loaded from a trained checkpoint by the caller.
    } else if (o.vit.weights.empty()) {
      log_info("encoder: ViT-", o.vit.size,
               " starts from random weights (no DINOv3 checkpoint given in "
               "encoder.vit.weights; none ships with this project)");
    } else {
      load_dinov3_safetensors(vit, o.vit.weights);
      log_info("encoder: loaded DINOv3 weights from ", o.vit.weights);
    }
  }
  if (o.cnn) cnn = register_module("cnn", CNNEncoder(o.cnn_options));
}

int64_t DualEncoderImpl::dino_dim() const {
  return vit ? vit->dim() : 0;
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
  if (cnn) f.cnn = cnn->forward(x);
  return f;
}

}  // namespace isplat
