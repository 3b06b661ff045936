// Bilinear lookup in a row-major float map at continuous pixel coordinates (pixel centres at +0.5).
#pragma once
#include <algorithm>
#include <cstdint>

namespace isplat {

// m is [H, W]; coordinates are clamped to the outer pixel centres (border padding).
inline float bilinear_at(const float* m, int64_t H, int64_t W, double u, double v) {
  const double x = std::clamp(u - 0.5, 0.0, static_cast<double>(W - 1)),
               y = std::clamp(v - 0.5, 0.0, static_cast<double>(H - 1));
  const int64_t j0 = std::min<int64_t>(static_cast<int64_t>(x), W - 1),
                i0 = std::min<int64_t>(static_cast<int64_t>(y), H - 1);
  const int64_t j1 = std::min(j0 + 1, W - 1), i1 = std::min(i0 + 1, H - 1);
  const double fx = x - j0, fy = y - i0;
  return static_cast<float>((m[i0 * W + j0] * (1 - fx) + m[i0 * W + j1] * fx) * (1 - fy) +
                            (m[i1 * W + j0] * (1 - fx) + m[i1 * W + j1] * fx) * fy);
}

}  // namespace isplat
