// Grid-hash kNN: points bucketed by cell (counting sort), then rings of cells searched per point in parallel.
#include "loss/knn.h"

#include <ATen/Parallel.h>
#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/error.h"

namespace isplat {

torch::Tensor knn_2d(const torch::Tensor& points, int64_t k) {
  ISPLAT_CHECK(points.dim() == 2 && points.size(1) == 2, "knn_2d: points must be [N, 2], got ", points.sizes());
  ISPLAT_CHECK(k >= 1, "knn_2d: k must be >= 1");
  auto p = points.detach().to(torch::kFloat32).contiguous();
  const int64_t N = p.size(0);
  auto out = torch::empty({N, k}, torch::kInt64);
  if (N == 0) return out;
  const float* xy = p.data_ptr<float>();
  float x0 = xy[0], x1 = xy[0], y0 = xy[1], y1 = xy[1];
  for (int64_t i = 0; i < N; ++i) {
    x0 = std::min(x0, xy[2 * i]), x1 = std::max(x1, xy[2 * i]);
    y0 = std::min(y0, xy[2 * i + 1]), y1 = std::max(y1, xy[2 * i + 1]);
  }
  ISPLAT_CHECK(std::isfinite(x0) && std::isfinite(x1) && std::isfinite(y0) && std::isfinite(y1),
               "knn_2d: non-finite points");
  // About 2 points per cell on average.
  const double area = std::max(1e-12, static_cast<double>(x1 - x0) * (y1 - y0));
  const double cell = std::max(1e-6, std::sqrt(2.0 * area / N));
  const int64_t gw = std::min<int64_t>(4096, static_cast<int64_t>((x1 - x0) / cell) + 1);
  const int64_t gh = std::min<int64_t>(4096, static_cast<int64_t>((y1 - y0) / cell) + 1);
  const double sx = gw / std::max(1e-12, static_cast<double>(x1 - x0) * (1 + 1e-9)),
               sy = gh / std::max(1e-12, static_cast<double>(y1 - y0) * (1 + 1e-9));
  auto cell_of = [&](int64_t i, int64_t& cx, int64_t& cy) {
    cx = std::min(gw - 1, static_cast<int64_t>((xy[2 * i] - x0) * sx));
    cy = std::min(gh - 1, static_cast<int64_t>((xy[2 * i + 1] - y0) * sy));
  };
  std::vector<int64_t> start(static_cast<size_t>(gw * gh) + 1, 0), order(static_cast<size_t>(N));
  for (int64_t i = 0; i < N; ++i) {
    int64_t cx, cy;
    cell_of(i, cx, cy);
    ++start[cy * gw + cx + 1];
  }
  for (size_t c = 1; c < start.size(); ++c) start[c] += start[c - 1];
  std::vector<int64_t> fill(start.begin(), start.end() - 1);
  for (int64_t i = 0; i < N; ++i) {  // stable: points keep index order within a cell
    int64_t cx, cy;
    cell_of(i, cx, cy);
    order[fill[cy * gw + cx]++] = i;
  }
  const double cw = 1.0 / sx, ch = 1.0 / sy;  // cell size in point units
  int64_t* o = out.data_ptr<int64_t>();
  at::parallel_for(0, N, 1024, [&](int64_t b, int64_t e) {
    std::vector<std::pair<float, int64_t>> best;
    for (int64_t i = b; i < e; ++i) {
      int64_t cx, cy;
      cell_of(i, cx, cy);
      best.clear();
      const float px = xy[2 * i], py = xy[2 * i + 1];
      for (int64_t r = 0;; ++r) {
        // Visit the ring of cells at Chebyshev distance r.
        for (int64_t gy = cy - r; gy <= cy + r; ++gy) {
          if (gy < 0 || gy >= gh) continue;
          const bool edge_row = gy == cy - r || gy == cy + r;
          for (int64_t gx = cx - r; gx <= cx + r; gx += (edge_row || r == 0) ? 1 : 2 * r) {
            if (gx < 0 || gx >= gw) continue;
            for (int64_t s = start[gy * gw + gx]; s < start[gy * gw + gx + 1]; ++s) {
              const int64_t j = order[s];
              if (j == i) continue;
              const float dx = xy[2 * j] - px, dy = xy[2 * j + 1] - py;
              best.emplace_back(dx * dx + dy * dy, j);
            }
          }
        }
        const bool covers_all = cx - r <= 0 && cy - r <= 0 && cx + r >= gw - 1 && cy + r >= gh - 1;
        if (static_cast<int64_t>(best.size()) >= k || covers_all) {
          // Points beyond ring r are at least r * cell away: stop once the k-th found is closer.
          const int64_t m = std::min<int64_t>(k, static_cast<int64_t>(best.size()));
          std::partial_sort(best.begin(), best.begin() + m, best.end());
          const double reach = r * std::min(cw, ch);
          if (covers_all || (m == k && best[k - 1].first <= reach * reach)) break;
        }
      }
      const int64_t m = std::min<int64_t>(k, static_cast<int64_t>(best.size()));
      for (int64_t q = 0; q < k; ++q) o[i * k + q] = q < m ? best[q].second : i;
    }
  });
  return out;
}

}  // namespace isplat
