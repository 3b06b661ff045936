// Panel layout with OpenCV; one writer for every example image in the project.
#include "io/panel.h"

#include <torch/torch.h>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "io/image_io.h"
#include "io/tensor_image.h"

namespace isplat {

void write_panel(const std::string& path, const std::vector<std::vector<torch::Tensor>>& rows) {
  ISPLAT_CHECK(!rows.empty() && !rows[0].empty(), path, ": an image panel needs at least one cell");
  std::vector<cv::Mat> lines;
  for (const auto& row : rows) {
    std::vector<cv::Mat> cells;
    for (const auto& t : row) {
      ISPLAT_CHECK(t.dim() == 3 && (t.size(0) == 3 || t.size(0) == 1), path, ": panel cell has shape ", t.sizes(),
                   ", expected [3,H,W] or [1,H,W]");
      auto c = t.detach().to(torch::kFloat32).clamp(0, 1);
      if (c.size(0) == 1) c = c.expand({3, -1, -1});
      cells.push_back(tensor_to_image(c.contiguous()));
    }
    cv::Mat line;
    cv::hconcat(cells, line);
    lines.push_back(line);
  }
  cv::Mat panel;
  cv::vconcat(lines, panel);
  write_image(path, panel);
}

torch::Tensor outline_mask(const torch::Tensor& image, const torch::Tensor& mask) {
  auto m = (mask.detach().to(torch::kFloat32) > 0.5).to(torch::kFloat32);
  auto img = image.detach().to(torch::kFloat32).clamp(0, 1);
  auto dimmed = img * (0.35 + 0.65 * m.unsqueeze(0));
  // Border: inside pixels with an outside 4-neighbour (max-pool of the outside set).
  auto outside = (1 - m).view({1, 1, m.size(0), m.size(1)});
  auto near_outside = torch::max_pool2d(outside, {3, 3}, {1, 1}, {1, 1}).view_as(m);
  auto border = (m * near_outside).unsqueeze(0);
  auto colour = torch::tensor({1.0f, 0.85f, 0.0f}).view({3, 1, 1});
  return dimmed * (1 - border) + colour * border;
}

}  // namespace isplat
