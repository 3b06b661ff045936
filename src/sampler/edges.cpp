// Edges and hidden surface: edge pixels, the band, the near side's shift, and the surface continued under silhouettes.
#include "sampler/edges.h"

#include <cmath>

#include "core/error.h"
#include "sampler/normals.h"

namespace isplat {
namespace sampling {

namespace {

// Valid pixels not surrounded by accepted triangles: one of the four quads around the pixel centre is outside
// the image or has a rejected (discontinuous or invalid) triangle. Faces leave a half-pixel gap around them.
// `area`: triangle_areas(g).
std::vector<int64_t> edge_pixels(const Grid& g, const std::vector<float>& area) {
  const int64_t H = g.H, W = g.W, Wq = W - 1;
  auto quad_ok = [&](int64_t i, int64_t j) { return area[(i * Wq + j) * 2] > 0 && area[(i * Wq + j) * 2 + 1] > 0; };
  std::vector<int64_t> out;
  for (int64_t i = 0; i < H; ++i)
    for (int64_t j = 0; j < W; ++j) {
      if (g.valid[i * W + j] == 0.0f) continue;
      bool inner = i > 0 && j > 0 && i + 1 < H && j + 1 < W;
      for (int64_t di = -1; inner && di <= 0; ++di)
        for (int64_t dj = -1; inner && dj <= 0; ++dj) inner = quad_ok(i + di, j + dj);
      if (!inner) out.push_back(i * W + j);
    }
  return out;
}

// The valid 8-neighbours of pixel p that lie beyond a depth discontinuity behind it, into `out`.
void farther_neighbours(const Grid& g, int64_t p, std::vector<int64_t>& out) {
  out.clear();
  const int64_t i = p / g.W, j = p % g.W;
  for (int64_t di = -1; di <= 1; ++di)
    for (int64_t dj = -1; dj <= 1; ++dj) {
      const int64_t y = i + di, x = j + dj, q = y * g.W + x;
      if ((di == 0 && dj == 0) || y < 0 || x < 0 || y >= g.H || x >= g.W || g.valid[q] == 0.0f) continue;
      if (g.depth[q] > g.depth[p] && depths_apart(g.depth[p], g.depth[q])) out.push_back(q);
    }
}

// The near-side edge pixels (those with farther neighbours) widened by `band` steps to 8-neighbours on the same
// surface (valid, not apart in depth), as a mask; the other edge pixels are set in it as themselves.
std::vector<uint8_t> near_band(const Grid& g, const std::vector<int64_t>& edges, int64_t band) {
  const int64_t H = g.H, W = g.W;
  std::vector<uint8_t> in(static_cast<size_t>(H * W), 0);
  std::vector<int64_t> front, next, far;
  for (int64_t p : edges) {
    in[p] = 1;
    farther_neighbours(g, p, far);
    if (!far.empty()) front.push_back(p);
  }
  for (int64_t step = 0; step < band && !front.empty(); ++step, front.swap(next)) {
    next.clear();
    for (int64_t p : front)
      for (int64_t di = -1; di <= 1; ++di)
        for (int64_t dj = -1; dj <= 1; ++dj) {
          const int64_t y = p / W + di, x = p % W + dj, q = y * W + x;
          if (y < 0 || x < 0 || y >= H || x >= W || in[q] || g.valid[q] == 0.0f) continue;
          if (depths_apart(g.depth[p], g.depth[q])) continue;
          in[q] = 1;
          next.push_back(q);
        }
  }
  return in;
}

}  // namespace

std::vector<int64_t> edge_band_pixels(const Grid& g, std::vector<float>& area, int64_t band, int64_t max_pixels) {
  const std::vector<int64_t> edges = edge_pixels(g, area);
  if (band <= 0) return edges;
  const int64_t H = g.H, W = g.W, Wq = W - 1;
  const std::vector<uint8_t> in = near_band(g, edges, band);
  std::vector<int64_t> out;
  for (int64_t p = 0; p < H * W; ++p)
    if (in[p] && g.valid[p] != 0.0f) out.push_back(p);
  if (static_cast<int64_t>(out.size()) > max_pixels) return edges;
  std::vector<float> faces = area;
  bool any_face = false;
  for (int64_t i = 0; i + 1 < H; ++i)
    for (int64_t j = 0; j < Wq; ++j)
      for (int t = 0; t < 2; ++t) {
        int64_t r[3], c[3];
        triangle_pixels(i, j, t, r, c);
        float& a = faces[(i * Wq + j) * 2 + t];
        if (in[r[0] * W + c[0]] && in[r[1] * W + c[1]] && in[r[2] * W + c[2]]) a = 0.0f;
        any_face |= a > 0;
      }
  if (any_face) area = std::move(faces);  // a band over the whole image leaves the faces as they were
  return out;
}

namespace {

// True when edge pixel p lies on the near side of a depth edge (it has farther neighbours), so its footprint can
// spill past the silhouette onto the background. `away` gets the unit image direction from p towards those
// neighbours (0, 0 when they surround it evenly).
bool near_side(const Grid& g, int64_t p, std::vector<int64_t>& far, double* away) {
  farther_neighbours(g, p, far);
  double dx = 0, dy = 0;
  for (int64_t q : far) {
    const int64_t di = q / g.W - p / g.W, dj = q % g.W - p % g.W;
    const double len = std::sqrt(double(di * di + dj * dj));
    dx += dj / len, dy += di / len;
  }
  const double len = std::sqrt(dx * dx + dy * dy);
  away[0] = len > 1e-9 ? dx / len : 0.0, away[1] = len > 1e-9 ? dy / len : 0.0;
  return !far.empty();
}

// Inverse depth of the surface through valid pixel q, extrapolated as a plane to image point (u, v): its gradient
// along each axis comes from the neighbour on the side away from pixel p (the other side when that one is missing or
// across a discontinuity; flat when both are).
double extrapolated_inverse_depth(const Grid& g, int64_t q, int64_t p, double u, double v) {
  const int64_t qi = q / g.W, qj = q % g.W, pi = p / g.W, pj = p % g.W;
  const double wq = 1.0 / g.depth[q];
  auto slope = [&](int64_t di, int64_t dj) {  // di, dj: a unit step along one axis
    for (int sgn : {1, -1}) {
      const int64_t y = qi + sgn * di, x = qj + sgn * dj;
      if (y < 0 || x < 0 || y >= g.H || x >= g.W || g.valid[y * g.W + x] == 0.0f) continue;
      if (depths_apart(g.depth[q], g.depth[y * g.W + x])) continue;
      return (1.0 / g.depth[y * g.W + x] - wq) * sgn;
    }
    return 0.0;
  };
  const int64_t away_i = qi >= pi ? 1 : -1, away_j = qj >= pj ? 1 : -1;
  return wq + slope(0, away_j) * away_j * (u - (qj + 0.5)) + slope(away_i, 0) * away_i * (v - (qi + 0.5));
}

}  // namespace

void shift_edge_supports(const Grid& g, const Output& o, const std::vector<int64_t>& pixels, double shift) {
  if (shift == 0.0) return;  // nothing moves
  std::vector<int64_t> far;
  for (size_t k = 0; k < pixels.size(); ++k) {
    double away[2];
    if (!near_side(g, pixels[k], far, away) || (away[0] == 0.0 && away[1] == 0.0)) continue;
    o.uv[2 * k] -= static_cast<float>(shift * away[0]);
    o.uv[2 * k + 1] -= static_cast<float>(shift * away[1]);
  }
}

Behind behind_places(const Grid& g, const std::vector<int64_t>& pixels, int64_t layers) {
  Behind b;
  const int64_t HW = g.H * g.W;
  std::vector<int64_t> far;
  for (int64_t p : pixels) {
    double away[2];
    if (!near_side(g, p, far, away)) continue;
    const int64_t i = p / g.W, j = p % g.W;
    double c[3] = {0, 0, 0}, farthest = 0;
    int64_t from = p;
    for (int64_t q : far) {
      for (int k = 0; k < 3; ++k) c[k] += g.image[k * HW + q];
      if (g.depth[q] > farthest) farthest = g.depth[q], from = q;
    }
    const double n = static_cast<double>(far.size());
    const bool flat = away[0] == 0.0 && away[1] == 0.0;  // no inward direction: one place, under the pixel
    for (int64_t s = 0; s < (flat ? 1 : layers); ++s) {  // the first layer under the edge pixel itself
      const double u = j + 0.5 - s * away[0], v = i + 0.5 - s * away[1];
      const int64_t x = static_cast<int64_t>(std::floor(u)), y = static_cast<int64_t>(std::floor(v));
      if (x < 0 || y < 0 || x >= g.W || y >= g.H || g.valid[y * g.W + x] == 0.0f) break;
      const double over = g.depth[y * g.W + x];  // the visible surface at the place
      double z = 0;
      for (int64_t q : far) {
        const double w = extrapolated_inverse_depth(g, q, p, u, v);
        const bool hidden = w > 0 && 1.0 / w > over && depths_apart(over, 1.0 / w);
        z += hidden ? 1.0 / w : g.depth[q];
      }
      z /= n;
      if (!(z > over && depths_apart(over, z))) break;
      b.u.push_back(u);
      b.v.push_back(v);
      b.depth.push_back(static_cast<float>(z));
      for (int k = 0; k < 3; ++k) b.color.push_back(static_cast<float>(c[k] / n));
      b.from.push_back(from);
    }
  }
  return b;
}

Behind select_places(const Behind& b, const std::vector<int64_t>& indices) {
  Behind out;
  for (int64_t k : indices) {
    out.u.push_back(b.u[k]), out.v.push_back(b.v[k]), out.depth.push_back(b.depth[k]), out.from.push_back(b.from[k]);
    for (int c = 0; c < 3; ++c) out.color.push_back(b.color[3 * k + c]);
  }
  return out;
}

void write_behind(const Grid& g, const Output& o, const Behind& b, int64_t count, int64_t first) {
  for (int64_t k = 0; k < count; ++k) {
    const int64_t t = first + k;
    o.uv[2 * t] = static_cast<float>(b.u[k]), o.uv[2 * t + 1] = static_cast<float>(b.v[k]);
    o.depth[t] = b.depth[k];
    for (int c = 0; c < 3; ++c) o.color[3 * t + c] = b.color[3 * k + c];
    o.area[t] = static_cast<float>(double(b.depth[k]) * b.depth[k] / (g.fx * g.fy));
  }
}

void behind_normals(const Grid& g, Supports& s, const Behind& b, int64_t count, int64_t first) {
  float* n = s.normal.data_ptr<float>();
  TriangleCrosses tc(g);
  int64_t first_at = -1, rows_at = -1;
  for (int64_t k = 0; k < count; ++k) {
    // The quad rows vertex_normal reads for pixel row i; consecutive places mostly share them.
    const int64_t q = b.from[k], i = q / g.W, first_row = std::max<int64_t>(i - 1, 0);
    const int64_t rows = std::max<int64_t>(std::min(i, g.H - 2) - first_row + 1, 0);
    if (first_row != first_at || rows != rows_at) tc.reset(first_row, rows), first_at = first_row, rows_at = rows;
    vertex_normal(g, tc, i, q % g.W, n + 3 * (first + k));
  }
}

}  // namespace sampling
}  // namespace isplat
