// Byte masks over an image's pixels (row-major, nonzero = set), in plain C++ for the samplers and measures.
#pragma once
#include <cstdint>
#include <vector>

namespace isplat {

// The mask grown by `radius` pixels in every direction (a (2r+1)² square, i.e. Chebyshev distance <= r),
// clipped to the image; radius <= 0 returns it unchanged (as 0/1).
std::vector<uint8_t> dilate_square(const std::vector<uint8_t>& mask, int64_t height, int64_t width, int64_t radius);

}  // namespace isplat
