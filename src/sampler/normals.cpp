// Surface normals at supports: each used pixel's normal computed once, in bands of rows that compute each triangle
// once.
#include "sampler/normals.h"

#include <torch/torch.h>

#include <cmath>
#include <memory>

namespace isplat {
namespace sampling {

void vertex_normal(const Grid& g, TriangleCrosses& tc, int64_t i, int64_t j, float* n) {
  double X[3], acc[3] = {0, 0, 0};
  backproject(g, j + 0.5, i + 0.5, g.depth[i * g.W + j], X);
  for (int64_t qi = std::max<int64_t>(i - 1, 0); qi <= std::min(i, g.H - 2); ++qi)
    for (int64_t qj = std::max<int64_t>(j - 1, 0); qj <= std::min(j, g.W - 2); ++qj)
      for (int t = 0; t < 2; ++t) {
        int64_t r[3], c[3];
        triangle_pixels(qi, qj, t, r, c);
        if (!((r[0] == i && c[0] == j) || (r[1] == i && c[1] == j) || (r[2] == i && c[2] == j))) continue;
        const double* cr = tc.at(qi, qj, t);
        if (cr == nullptr) continue;
        const double facing = cr[0] * X[0] + cr[1] * X[1] + cr[2] * X[2] > 0 ? -1.0 : 1.0;
        for (int k = 0; k < 3; ++k) acc[k] += facing * cr[k];
      }
  double len = std::sqrt(acc[0] * acc[0] + acc[1] * acc[1] + acc[2] * acc[2]);
  if (!(len > 0)) {
    for (int k = 0; k < 3; ++k) acc[k] = -X[k];
    len = std::sqrt(acc[0] * acc[0] + acc[1] * acc[1] + acc[2] * acc[2]);
  }
  for (int k = 0; k < 3; ++k) n[k] = static_cast<float>(acc[k] / len);
}

void write_normals(const Grid& g, Supports& s) {
  const int64_t N = s.count();
  const float* uv = s.uv.data_ptr<float>();
  std::unique_ptr<int64_t[]> pixel(new int64_t[N]);  // not zero-filled: every entry is written
  at::parallel_for(0, N, 4096, [&](int64_t b, int64_t e) {
    for (int64_t k = b; k < e; ++k) {
      int64_t i = std::clamp<int64_t>(static_cast<int64_t>(uv[2 * k + 1]), 0, g.H - 1),
              j = std::clamp<int64_t>(static_cast<int64_t>(uv[2 * k]), 0, g.W - 1);
      if (g.valid[i * g.W + j] == 0.0f) {  // a support between pixels takes the nearest valid corner
        const double fu = uv[2 * k] - 0.5, fv = uv[2 * k + 1] - 0.5;
        double best = 1e30;
        for (int64_t di = 0; di <= 1; ++di)
          for (int64_t dj = 0; dj <= 1; ++dj) {
            const int64_t ii = std::clamp<int64_t>(static_cast<int64_t>(std::floor(fv)) + di, 0, g.H - 1),
                          jj = std::clamp<int64_t>(static_cast<int64_t>(std::floor(fu)) + dj, 0, g.W - 1);
            const double d2 = (ii - fv) * (ii - fv) + (jj - fu) * (jj - fu);
            if (g.valid[ii * g.W + jj] != 0.0f && d2 < best) best = d2, i = ii, j = jj;
          }
      }
      pixel[k] = i * g.W + j;
    }
  });
  std::vector<uint8_t> used(static_cast<size_t>(g.H * g.W), 0);
  for (int64_t k = 0; k < N; ++k) used[pixel[k]] = 1;
  std::unique_ptr<float[]> map(new float[g.H * g.W * 3]);  // written where used, read only there
  constexpr int64_t kBand = 16;
  at::parallel_for(0, (g.H + kBand - 1) / kBand, 1, [&](int64_t b, int64_t e) {
    TriangleCrosses tc(g);
    for (int64_t band = b; band < e; ++band) {
      const int64_t r0 = band * kBand, r1 = std::min(g.H, r0 + kBand);
      const int64_t q0 = std::max<int64_t>(r0 - 1, 0), q1 = std::min(r1, g.H - 1);  // quad rows touching the band
      tc.reset(q0, std::max<int64_t>(q1 - q0, 0));
      for (int64_t p = r0 * g.W; p < r1 * g.W; ++p)
        if (used[p]) vertex_normal(g, tc, p / g.W, p % g.W, &map[3 * p]);
    }
  });
  s.normal = torch::empty({N, 3});
  float* n = s.normal.data_ptr<float>();
  at::parallel_for(0, N, 4096, [&](int64_t b, int64_t e) {
    for (int64_t k = b; k < e; ++k) std::copy_n(&map[3 * pixel[k]], 3, n + 3 * k);
  });
}

}  // namespace sampling
}  // namespace isplat
