// Square dilation of a byte mask, separable: along rows, then along columns.
#include "geometry/pixel_mask.h"

#include <algorithm>

#include "core/error.h"

namespace isplat {

std::vector<uint8_t> dilate_square(const std::vector<uint8_t>& mask, int64_t height, int64_t width, int64_t radius) {
  ISPLAT_CHECK(static_cast<int64_t>(mask.size()) == height * width, "dilate_square: mask has ", mask.size(),
               " pixels, expected ", height, "x", width);
  const int64_t r = std::max<int64_t>(radius, 0);
  std::vector<uint8_t> rows(mask.size(), 0), out(mask.size(), 0);
  for (int64_t i = 0; i < height; ++i)
    for (int64_t j = 0; j < width; ++j)
      if (mask[i * width + j])
        for (int64_t b = std::max<int64_t>(0, j - r); b <= std::min(width - 1, j + r); ++b) rows[i * width + b] = 1;
  for (int64_t i = 0; i < height; ++i)
    for (int64_t j = 0; j < width; ++j)
      if (rows[i * width + j])
        for (int64_t a = std::max<int64_t>(0, i - r); a <= std::min(height - 1, i + r); ++a) out[a * width + j] = 1;
  return out;
}

}  // namespace isplat
