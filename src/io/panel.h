// Image panels: a grid of tensor images written as one PNG (validation and evaluation examples).
#pragma once
#include <string>
#include <vector>

#include <torch/types.h>

namespace isplat {

// rows[r][c] is a [3,H,W] or [1,H,W] float image in [0,1] (clamped); all cells share H and W. Atomic write.
void write_panel(const std::string& path, const std::vector<std::vector<torch::Tensor>>& rows);

// `image` [3,H,W] with the pixels outside `mask` [H,W] (1 = inside) dimmed and the mask's border outlined,
// so a panel shows the raw prediction together with the scored region.
torch::Tensor outline_mask(const torch::Tensor& image, const torch::Tensor& mask);

}  // namespace isplat
