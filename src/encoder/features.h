// The encoder's output: the two feature maps the decoder queries (light header, no network types).
#pragma once
#include <torch/types.h>

namespace isplat {

struct EncoderFeatures {
  torch::Tensor dino;  // [B,C_d,H'/16,W'/16] or undefined when the branch is off
  torch::Tensor cnn;   // [B,128,H'/4,W'/4] or undefined
};

}  // namespace isplat
