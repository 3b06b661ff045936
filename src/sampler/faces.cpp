// Area faces: stratified, deterministic allocation of supports over the triangles' cumulative area.
#include "sampler/faces.h"

#include <cmath>

#include "core/error.h"
#include "geometry/bilinear.h"

namespace isplat {
namespace sampling {

double sample_faces(const Grid& g, std::vector<float> area, int64_t n, uint64_t seed, const Output& o, int64_t first,
                    const float* weight, double image_share, double pixel_floor) {
  const int64_t Hq = g.H - 1, Wq = g.W - 1;
  std::vector<double> row_sum(static_cast<size_t>(Hq), 0.0);
  for_each_row(Hq, [&](int64_t i) {
    double s = 0;
    for (int64_t q = i * Wq * 2; q < (i + 1) * Wq * 2; ++q) s += area[q];
    row_sum[i] = s;
  });
  const double total = row_offsets(row_sum, 0.0)[Hq];
  ISPLAT_CHECK(total > 0,
               "sampler: the depth map has no valid triangle (all depth is invalid, NaN/inf/<=0, or broken "
               "by discontinuities)");
  if (n == 0) return total;
  // Weighted areas (the allocation's measure) and their total.
  double total_w = total;
  // The allocation's measure differs from the area: keep the area, each support's share is computed from both.
  std::vector<float> raw;
  if (weight != nullptr || image_share > 0 || pixel_floor > 0) raw = area;
  if (weight != nullptr) {
    for_each_row(Hq, [&](int64_t i) {
      double s = 0;
      for (int64_t j = 0; j < Wq; ++j)
        for (int t = 0; t < 2; ++t) {
          float& a = area[(i * Wq + j) * 2 + t];
          if (a > 0) a *= weight[i * g.W + j + t];  // the triangle's first vertex: valid, so weight >= floor > 0
          s += a;
        }
      row_sum[i] = s;
    });
    total_w = row_offsets(row_sum, 0.0)[Hq];
  }
  if (image_share > 0 || pixel_floor > 0) {
    // measure = (1 - share) * measure + share * (total / accepted triangles): the total is unchanged. Then
    // the floor: no triangle's measure below pixel_floor * that even share (the total grows).
    int64_t accepted = 0;
    for (float a : area) accepted += a > 0;
    const double even = total_w / static_cast<double>(accepted);
    for_each_row(Hq, [&](int64_t i) {
      double s = 0;
      for (int64_t q = i * Wq * 2; q < (i + 1) * Wq * 2; ++q) {
        float& a = area[q];
        if (a > 0) a = static_cast<float>(std::max((1.0 - image_share) * a + image_share * even, pixel_floor * even));
        s += a;
      }
      row_sum[i] = s;
    });
    total_w = row_offsets(row_sum, 0.0)[Hq];
  }
  // Systematic (stratified) allocation over the cumulative area, in exact integer arithmetic so that
  // row boundaries agree and rejected (zero-area) triangles can never receive a support:
  // triangle q gets floor((C_end*n + X)/Q) - floor((C_start*n + X)/Q) supports.
  std::vector<int64_t> qarea(area.size());
  std::vector<int64_t> row_qsum(static_cast<size_t>(Hq), 0);
  const double quantum = std::ldexp(1.0, 40) / total_w;
  for_each_row(Hq, [&](int64_t i) {
    int64_t rs = 0;
    for (int64_t q = i * Wq * 2; q < (i + 1) * Wq * 2; ++q) rs += qarea[q] = std::llround(area[q] * quantum);
    row_qsum[i] = rs;
  });
  const std::vector<int64_t> row_qstart = row_offsets<int64_t>(row_qsum, 0);
  const __int128 Q = row_qstart[Hq];
  ISPLAT_CHECK(Q > 0, "sampler: the depth map has no valid triangle");
  const __int128 X = static_cast<__int128>(unit(seed * 2654435761ull + 17) * static_cast<double>(Q));
  std::vector<int32_t> counts(area.size());
  std::vector<int64_t> row_count(static_cast<size_t>(Hq), 0);
  for_each_row(Hq, [&](int64_t i) {
    __int128 c = row_qstart[i];
    __int128 prev = (c * n + X) / Q;
    int64_t rc = 0;
    for (int64_t q = i * Wq * 2; q < (i + 1) * Wq * 2; ++q) {
      c += qarea[q];
      const __int128 cur = (c * n + X) / Q;
      counts[q] = static_cast<int32_t>(cur - prev);
      rc += counts[q];
      prev = cur;
    }
    row_count[i] = rc;
  });
  const std::vector<int64_t> row_first = row_offsets(row_count, first);
  ISPLAT_CHECK(row_first[Hq] - first == n, "sampler: allocated ", row_first[Hq] - first, " supports, expected ", n);
  // R2 low-discrepancy sequence inside each triangle, offset per triangle.
  constexpr double g2 = 1.32471795724474602596;
  const double a1 = 1.0 / g2, a2 = 1.0 / (g2 * g2);
  for_each_row(Hq, [&](int64_t i) {
    int64_t k = row_first[i];
    for (int64_t j = 0; j < Wq; ++j)
      for (int t = 0; t < 2; ++t) {
        const int64_t q = (i * Wq + j) * 2 + t;
        const int32_t cnt = counts[q];
        if (cnt == 0) continue;
        int64_t r[3], c[3];
        triangle_pixels(i, j, t, r, c);
        // Bilinear depth only when the quad's other triangle is accepted too (no discontinuity).
        const bool quad_ok = area[(i * Wq + j) * 2 + (1 - t)] > 0;
        // Allocation is proportional to area, so every support stands for the same area, total / n
        // (= A_t / n_t in expectation). Unlike A_t / n_t it stays right when n is below the triangle
        // count, where most triangles get 0 or 1 support and A_t / n_t would leave holes.
        // With a measure m other than the area A: each support stands for A_q · total_m / (n · m_q).
        const float rep = static_cast<float>(raw.empty() ? total / n : raw[q] * total_w / (n * double(area[q])));
        const double s1 = unit(seed ^ (static_cast<uint64_t>(q) * 0x9E3779B97F4A7C15ull)),
                     s2 = unit(seed ^ (static_cast<uint64_t>(q) * 0xC2B2AE3D27D4EB4Full + 7));
        for (int32_t m = 0; m < cnt; ++m, ++k) {
          double b1 = s1 + (m + 1) * a1, b2 = s2 + (m + 1) * a2;
          b1 -= std::floor(b1);
          b2 -= std::floor(b2);
          if (b1 + b2 > 1.0) b1 = 1.0 - b1, b2 = 1.0 - b2;
          const double u = c[0] + 0.5 + b1 * (c[1] - c[0]) + b2 * (c[2] - c[0]);
          const double v = r[0] + 0.5 + b1 * (r[1] - r[0]) + b2 * (r[2] - r[0]);
          float z;
          if (quad_ok) {
            z = bilinear_at(g.depth, g.H, g.W, u, v);
          } else {
            const float z0 = g.depth[r[0] * g.W + c[0]], z1 = g.depth[r[1] * g.W + c[1]],
                        z2 = g.depth[r[2] * g.W + c[2]];
            z = static_cast<float>(z0 + b1 * (z1 - z0) + b2 * (z2 - z0));
          }
          write_support(g, o, k, u, v, z, rep);
        }
      }
  });
  return total;
}

}  // namespace sampling
}  // namespace isplat
