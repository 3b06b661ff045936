// ImageNet mean/std normalization shared by the ViT, the CNN-based nets and the frozen feature networks.
#include "nets/imagenet.h"

#include <torch/torch.h>

namespace isplat {

torch::Tensor imagenet_mean() {
  return torch::tensor({kImageNetMean[0], kImageNetMean[1], kImageNetMean[2]}).view({1, 3, 1, 1});
}
torch::Tensor imagenet_std() {
  return torch::tensor({kImageNetStd[0], kImageNetStd[1], kImageNetStd[2]}).view({1, 3, 1, 1});
}
torch::Tensor imagenet_normalize(const torch::Tensor& x) {
  return (x - imagenet_mean().to(x.dtype())) / imagenet_std().to(x.dtype());
}

}  // namespace isplat
