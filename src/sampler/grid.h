// Internal to the sampler: the depth map as a grid of pixel-quad triangles, and the support writers every strategy
// shares (allocation, pixel-centre supports, area rescaling, fixed-chunk row loops).
#pragma once
#include <ATen/Parallel.h>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "sampler/sampler.h"

namespace isplat {
namespace sampling {

struct Grid {
  const float* depth;
  const float* valid;
  const float* image;  // [3,H,W]
  int64_t H, W;
  double fx, fy, cx, cy, skew;
};

// Checks the inputs and keeps float32 contiguous copies in the *_keep tensors, which the grid points into.
Grid make_grid(const torch::Tensor& depth, const torch::Tensor& valid, const torch::Tensor& K,
               const torch::Tensor& image, torch::Tensor& d_keep, torch::Tensor& v_keep, torch::Tensor& i_keep);

inline void backproject(const Grid& g, double u, double v, double z, double* X) {
  const double y = (v - g.cy) / g.fy;
  X[0] = (u - g.cx - g.skew * y) / g.fx * z;
  X[1] = y * z;
  X[2] = z;
}

// Triangle t of quad (i, j): 0 = (i,j),(i,j+1),(i+1,j); 1 = (i,j+1),(i+1,j+1),(i+1,j).
inline void triangle_pixels(int64_t i, int64_t j, int t, int64_t (&r)[3], int64_t (&c)[3]) {
  if (t == 0) {
    r[0] = i, c[0] = j, r[1] = i, c[1] = j + 1, r[2] = i + 1, c[2] = j;
  } else {
    r[0] = i, c[0] = j + 1, r[1] = i + 1, c[1] = j + 1, r[2] = i + 1, c[2] = j;
  }
}

// 64-bit mix for per-triangle sequence offsets.
inline uint64_t mix(uint64_t x) {
  x ^= x >> 33;
  x *= 0xff51afd7ed558ccdull;
  x ^= x >> 33;
  x *= 0xc4ceb9fe1a85ec53ull;
  return x ^ (x >> 33);
}

inline double unit(uint64_t x) {
  return static_cast<double>(mix(x) >> 11) * (1.0 / 9007199254740992.0);
}

struct Output {
  float *uv, *depth, *color, *area;
};

// Runs fn(i) for rows 0..rows-1 in fixed chunks (independent of the thread count), so sums and
// outputs are reproducible.
template <class F>
void for_each_row(int64_t rows, const F& fn) {
  constexpr int64_t kRowChunk = 8;
  at::parallel_for(0, (rows + kRowChunk - 1) / kRowChunk, 1, [&](int64_t b, int64_t e) {
    for (int64_t chunk = b; chunk < e; ++chunk)
      for (int64_t i = chunk * kRowChunk; i < std::min(rows, (chunk + 1) * kRowChunk); ++i) fn(i);
  });
}

// Row offsets from per-row sums: [start, start + s0, start + s0 + s1, ...].
template <class T>
std::vector<T> row_offsets(const std::vector<T>& per_row, T start) {
  std::vector<T> out(per_row.size() + 1, start);
  for (size_t i = 0; i < per_row.size(); ++i) out[i + 1] = out[i] + per_row[i];
  return out;
}

// Twice the area vector (e1 x e2) of triangle t of quad (i, j); false when a vertex is invalid or the triangle spans
// a depth discontinuity.
bool triangle_cross(const Grid& g, int64_t i, int64_t j, int t, double* cross);

// Area of an accepted triangle, 0 when a vertex is invalid or it spans a depth discontinuity.
double triangle_area(const Grid& g, int64_t i, int64_t j, int t);

// The area of every triangle, (i * (W - 1) + j) * 2 + t for triangle t of quad (i, j); 0 when rejected.
std::vector<float> triangle_areas(const Grid& g);

// Writes support k at image point (u, v) with depth z, the bilinear colour there, and the area it stands for.
void write_support(const Grid& g, const Output& o, int64_t k, double u, double v, float z, float area);

// Footprint of pixel (i, j): the area of its quad's accepted triangles, else z^2 / (fx fy).
float pixel_area(const Grid& g, int64_t i, int64_t j);

Supports allocate(int64_t n);
Output pointers(Supports& s);

// Supports placed at pixels and on faces both stand for the surface: rescale the first `count` (all when negative)
// so their areas sum to `total` once.
void rescale_areas(Supports& s, double total, int64_t count = -1);

// Supports 0..count-1 at the centres of the given pixels (flat indices).
void write_pixel_supports(const Grid& g, const Output& o, const std::vector<int64_t>& pixels, int64_t count);

// `count` of the pixels, spread evenly over the list (all of them when count equals its size).
std::vector<int64_t> spread(const std::vector<int64_t>& pixels, int64_t count);

}  // namespace sampling
}  // namespace isplat
