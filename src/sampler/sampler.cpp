// Area-weighted stratified support sampling: per-row passes over raw pointers with at::parallel_for.
// Rows are processed in a fixed chunking, so results do not depend on the thread count.
#include "sampler/sampler.h"

#include <ATen/Parallel.h>
#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <numeric>

#include "core/config.h"
#include "core/error.h"
#include "geometry/bilinear.h"
#include "geometry/camera_torch.h"
#include "geometry/pixel_mask.h"
#include "sampler/depth_fill.h"

namespace isplat {

void SamplerOptions::visit(ConfigVisitor& v) {
  v.field("mode", mode,
          "support placement: area-weighted on the depth surface (paper), one per pixel (ablation), "
          "or the release's gradient-priority vertices + area-weighted faces",
          {"area", "pixel", "vertex_face"});
  v.field("budget_mode", budget_mode,
          "fixed count; or per image pixel, per steradian of valid surface; or detail: per pixel, scaled by how "
          "much the image and surface vary there (see detail_floor)",
          {"fixed", "per_pixel", "solid_angle", "detail"});
  v.field("budget", budget, "number of supports when budget_mode = fixed (paper: 1.5M at 1536x1024)",
          Range::between(1, kMaxSupports));
  v.field("density", density, "supports per pixel (per_pixel) or per steradian (solid_angle)", Range::above(0));
  v.field("min_budget", min_budget, "lower bound for adaptive budgets", Range::between(1, kMaxSupports));
  v.field("max_budget", max_budget, "upper bound for adaptive budgets", Range::between(1, kMaxSupports));
  v.require("max_budget", min_budget <= max_budget, "must be >= sampler.min_budget");
  v.field("vertex_fraction", vertex_fraction, "vertex_face: fraction of supports on gradient-priority vertices",
          Range::unit());
  v.field("detail_floor", detail_floor,
          "detail budget: share of `density` a featureless, flat block gets (1 = per_pixel everywhere)",
          Range::between(0.01, 1.0));
  v.field("detail_ref", detail_ref,
          "detail budget: block detail (mean colour gradient + surface curvature per pixel) that earns the full "
          "density",
          Range::above(0.0));
  v.field("detail_block", detail_block, "detail budget: block size in pixels over which detail is averaged",
          Range::between(1, 256));
  v.field("image_share", image_share,
          "area mode: share of supports spread evenly per image pixel instead of by 3D area (0 = the paper's "
          "area sampling; near surfaces get more supports as it grows)",
          Range::unit());
  v.field("pixel_floor", pixel_floor,
          "area mode: no accepted triangle draws supports below this share of an even per-pixel spread (applied "
          "after image_share), so near surfaces keep at least that density; the rest still follows area (0 = off)",
          Range::between(0.0, 4.0));
  v.field("edge_supports", edge_supports,
          "area mode: also one support per valid pixel at a depth edge, hole or image border (where no accepted "
          "triangle surrounds it and faces leave a half-pixel gap), taken from the budget");
  v.field("edge_band", edge_band,
          "area mode with edge_supports: pixels within this many pixels of a depth edge, hole or border get a "
          "pixel-centre support too and triangles wholly inside the band get none (silhouettes on pixel rays, "
          "area sampling elsewhere); 0 = the edge pixels only",
          Range::between(0, 16));
  v.require("edge_band", edge_band == 0 || edge_supports, "needs sampler.edge_supports = true");
  v.field("edge_band_at", edge_band_at,
          "with edge_band: widen every edge pixel (all: depth edges, holes, the border) or only the near side of "
          "depth edges, over its own surface (near: the silhouettes whose footprints can spill onto a background; "
          "far sides, holes and the border keep faces up to their edge supports)",
          {"all", "near"});
  v.require("edge_band_at", edge_band_at == "all" || edge_band > 0, "near needs sampler.edge_band > 0");
  v.field("edge_shift", edge_shift,
          "area mode with edge_supports, or pixel mode: move each support at a depth edge's near side (area: the "
          "edge supports) this many pixels away from the farther surface, keeping its depth, colour and footprint, "
          "so silhouettes spill less onto the background (0 = at the pixel centre)",
          Range::between(0.0, 0.5));
  // edge_shift and edge_behind act on the supports at depth edges: every pixel's in pixel mode, the edge supports in
  // area mode (with a band, its pixels beside a depth edge: band supports are a pixel apart, so a near-side one moved
  // half a pixel in still overlaps the next).
  const bool at_edges = mode == "pixel" || (mode == "area" && edge_supports);
  const char* at_edges_needs =
      "needs sampler.mode = pixel, or sampler.mode = area with sampler.edge_supports = true (it acts on the supports "
      "at depth edges)";
  v.require("edge_shift", edge_shift == 0.0 || at_edges, at_edges_needs);
  v.field("edge_behind", edge_behind,
          "area mode with edge_supports, or pixel mode: continue the farther surface under each near-side "
          "silhouette pixel with up to this many supports, one pixel apart inwards while they stay hidden, on the "
          "farther neighbours' surfaces extrapolated as planes, in their colour, so what a new view uncovers beside "
          "a silhouette has surface (area mode: taken from the budget, at most half of it with the edge supports; "
          "pixel mode: on top of one per pixel; 0 = off)",
          Range::between(0, 4));
  v.require("edge_behind", edge_behind == 0 || at_edges, at_edges_needs);
  v.field("edge_behind_start", edge_behind_start,
          "with edge_behind: how many pixels in from the edge pixel's centre the first hidden support sits (0 = "
          "under the edge pixel, which a view near the source partly sees through)",
          Range::between(0, 2));
  v.require("edge_behind_start", edge_behind_start == 0 || edge_behind > 0, "needs sampler.edge_behind > 0");
  v.field("fill_px", fill_px,
          "before sampling, fill invalid depth within this many pixels of valid depth (push-pull in log depth), so "
          "small holes (sensor drop-outs, invalid prior pixels) get supports; the inside of larger missing regions "
          "(most of a sky) stays empty; 0 = off",
          Range::between(0, 256));
}

double discontinuity_threshold(double z_mean) {
  const double t = std::clamp(std::log10(std::max(z_mean, 1e-12)) / 2.0, 0.0, 1.0);
  return 1.05 + 0.05 * t;
}

bool depths_apart(double a, double b) {
  return std::max(a, b) / std::min(a, b) >= discontinuity_threshold(0.5 * (a + b));
}

namespace {

SamplerOptions without_fill(SamplerOptions o) {  // the options once fill_px has been applied
  o.fill_px = 0;
  return o;
}

FilledDepth fill_holes(const torch::Tensor& depth, const torch::Tensor& valid, const SamplerOptions& o) {
  return fill_depth_holes(depth, valid, o.fill_px);
}

struct Grid {
  const float* depth;
  const float* valid;
  const float* image;  // [3,H,W]
  int64_t H, W;
  double fx, fy, cx, cy, skew;
};

Grid make_grid(const torch::Tensor& depth, const torch::Tensor& valid, const torch::Tensor& K,
               const torch::Tensor& image, torch::Tensor& d_keep, torch::Tensor& v_keep, torch::Tensor& i_keep) {
  ISPLAT_CHECK(depth.dim() == 2, "sampler: depth must be [H, W], got ", depth.sizes());
  ISPLAT_CHECK(valid.sizes() == depth.sizes(), "sampler: valid ", valid.sizes(), " differs from depth ", depth.sizes());
  ISPLAT_CHECK(
      image.dim() == 3 && image.size(0) == 3 && image.size(1) == depth.size(0) && image.size(2) == depth.size(1),
      "sampler: image must be [3, H, W] matching depth ", depth.sizes(), ", got ", image.sizes());
  ISPLAT_CHECK(K.sizes() == torch::IntArrayRef({3, 3}), "sampler: K must be [3, 3], got ", K.sizes());
  d_keep = depth.detach().to(torch::kFloat32).contiguous();
  v_keep = usable_depth(d_keep, valid.detach()).to(torch::kFloat32).contiguous();
  i_keep = image.detach().to(torch::kFloat32).contiguous();
  auto Kd = K.detach().to(torch::kFloat64).contiguous();
  const double* k = Kd.data_ptr<double>();
  return {d_keep.data_ptr<float>(),
          v_keep.data_ptr<float>(),
          i_keep.data_ptr<float>(),
          depth.size(0),
          depth.size(1),
          k[0],
          k[4],
          k[2],
          k[5],
          k[1]};
}

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

// Twice the area vector (e1 x e2) of triangle t of quad (i, j); false when a vertex is invalid or the triangle spans
// a depth discontinuity.
bool triangle_cross(const Grid& g, int64_t i, int64_t j, int t, double* cross) {
  int64_t r[3], c[3];
  triangle_pixels(i, j, t, r, c);
  double z[3], P[3][3];
  for (int k = 0; k < 3; ++k) {
    const int64_t idx = r[k] * g.W + c[k];
    if (g.valid[idx] == 0.0f) return false;
    z[k] = g.depth[idx];
    backproject(g, c[k] + 0.5, r[k] + 0.5, z[k], P[k]);
  }
  const double zmin = std::min({z[0], z[1], z[2]}), zmax = std::max({z[0], z[1], z[2]});
  if (zmax / zmin >= discontinuity_threshold((z[0] + z[1] + z[2]) / 3.0)) return false;
  double e1[3], e2[3];
  for (int k = 0; k < 3; ++k) e1[k] = P[1][k] - P[0][k], e2[k] = P[2][k] - P[0][k];
  cross[0] = e1[1] * e2[2] - e1[2] * e2[1];
  cross[1] = e1[2] * e2[0] - e1[0] * e2[2];
  cross[2] = e1[0] * e2[1] - e1[1] * e2[0];
  return true;
}

// Area of an accepted triangle, 0 when a vertex is invalid or it spans a depth discontinuity.
double triangle_area(const Grid& g, int64_t i, int64_t j, int t) {
  double cr[3];
  if (!triangle_cross(g, i, j, t, cr)) return 0.0;
  return 0.5 * std::sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]);
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

void write_support(const Grid& g, const Output& o, int64_t k, double u, double v, float z, float area) {
  o.uv[2 * k] = static_cast<float>(u);
  o.uv[2 * k + 1] = static_cast<float>(v);
  o.depth[k] = z;
  for (int c = 0; c < 3; ++c) o.color[3 * k + c] = bilinear_at(g.image + c * g.H * g.W, g.H, g.W, u, v);
  o.area[k] = area;
}

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

// The area of every triangle, (i * (W - 1) + j) * 2 + t for triangle t of quad (i, j); 0 when rejected.
std::vector<float> triangle_areas(const Grid& g) {
  const int64_t Hq = g.H - 1, Wq = g.W - 1;
  ISPLAT_CHECK(Hq > 0 && Wq > 0, "sampler: depth map ", g.H, "x", g.W, " is too small to form triangles");
  std::vector<float> area(static_cast<size_t>(Hq * Wq * 2));
  for_each_row(Hq, [&](int64_t i) {
    for (int64_t j = 0; j < Wq; ++j)
      for (int t = 0; t < 2; ++t) area[(i * Wq + j) * 2 + t] = static_cast<float>(triangle_area(g, i, j, t));
  });
  return area;
}

// Area-weighted stratified sampling of n supports into o starting at `first`. Returns the total area.
// `area`: triangle_areas(g). `weight` (per pixel, or null): triangles are drawn in proportion to area × the
// weight of their quad's first vertex, and each support then stands for a share of area inversely
// proportional to that weight. `image_share` and `pixel_floor` as in SamplerOptions.
double sample_faces(const Grid& g, std::vector<float> area, int64_t n, uint64_t seed, const Output& o, int64_t first,
                    const float* weight = nullptr, double image_share = 0.0, double pixel_floor = 0.0) {
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

// Footprint of pixel (i, j): the area of its quad's accepted triangles, else z^2 / (fx fy).
float pixel_area(const Grid& g, int64_t i, int64_t j) {
  if (i + 1 < g.H && j + 1 < g.W) {
    const double a = triangle_area(g, i, j, 0) + triangle_area(g, i, j, 1);
    if (a > 0) return static_cast<float>(a);
  }
  const double z = g.depth[i * g.W + j];
  return static_cast<float>(z * z / (g.fx * g.fy));
}

Supports allocate(int64_t n) {
  Supports s;
  s.uv = torch::empty({n, 2});
  s.depth = torch::empty({n});
  s.color = torch::empty({n, 3});
  s.area = torch::empty({n});
  return s;
}

// Twice the area vectors of the triangles of quad rows [first, first + rows), each computed at most once, when a
// pixel around it first asks; a band of rows, small enough to stay in cache.
class TriangleCrosses {
 public:
  explicit TriangleCrosses(const Grid& g) : g_(g), Wq_(g.W - 1) {}
  void reset(int64_t first_row, int64_t rows) {
    first_ = first_row, rows_ = rows;
    cross_.resize(static_cast<size_t>(rows * Wq_ * 6));
    state_.assign(static_cast<size_t>(rows * Wq_ * 2), kUnknown);
  }
  // Null where triangle_cross rejects the triangle.
  const double* at(int64_t i, int64_t j, int t) {
    ISPLAT_CHECK(i >= first_ && i < first_ + rows_ && j >= 0 && j < Wq_, "sampler: quad (", i, ", ", j,
                 ") outside the cached rows [", first_, ", ", first_ + rows_, ")");
    const int64_t q = ((i - first_) * Wq_ + j) * 2 + t;
    if (state_[q] == kUnknown) state_[q] = triangle_cross(g_, i, j, t, &cross_[3 * q]) ? kAccepted : kRejected;
    return state_[q] == kAccepted ? &cross_[3 * q] : nullptr;
  }

 private:
  enum : uint8_t { kUnknown, kAccepted, kRejected };
  const Grid& g_;
  int64_t Wq_, first_ = 0, rows_ = 0;
  std::vector<double> cross_;
  std::vector<uint8_t> state_;
};

// The normal of the depth surface at pixel (i, j): the area-weighted mean of the accepted triangles that have the
// pixel centre as a vertex, turned to face the camera. Where none is accepted (a lone pixel, a silhouette), the
// surface is taken to face the camera: -X / |X|.
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

// Every support takes the surface normal at the valid pixel nearest its position. Each such pixel's normal is
// computed once, in bands of rows that compute each triangle once: O(pixels used), not six triangles per support.
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

Output pointers(Supports& s) {
  return {s.uv.data_ptr<float>(), s.depth.data_ptr<float>(), s.color.data_ptr<float>(), s.area.data_ptr<float>()};
}

// Supports placed at pixels and on faces both stand for the surface: rescale the first `count` (all when negative)
// so their areas sum to `total` once.
void rescale_areas(Supports& s, double total, int64_t count = -1) {
  torch::Tensor a = count < 0 ? s.area : s.area.narrow(0, 0, count);
  const double sum = a.sum().item<double>();
  if (sum > 0) a.mul_(total / sum);
}

// Supports 0..count-1 at the centres of the given pixels (flat indices).
void write_pixel_supports(const Grid& g, const Output& o, const std::vector<int64_t>& pixels, int64_t count) {
  at::parallel_for(0, count, 4096, [&](int64_t b, int64_t e) {
    for (int64_t k = b; k < e; ++k) {
      const int64_t p = pixels[k], i = p / g.W, j = p % g.W;
      write_support(g, o, k, j + 0.5, i + 0.5, g.depth[p], pixel_area(g, i, j));
    }
  });
}

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

// The edge pixels widened by `band` pixels over valid pixels, row-major: all of them (Chebyshev), or (near_only)
// the near side of depth edges over its own surface (near_band). The triangles whose three vertices all lie in the
// band get area 0, so faces leave the band to its pixel supports. A band of more than `max_pixels` would leave band
// pixels with neither kind of support, so the edge pixels alone are returned then.
std::vector<int64_t> edge_band_pixels(const Grid& g, std::vector<float>& area, int64_t band, bool near_only,
                                      int64_t max_pixels) {
  const std::vector<int64_t> edges = edge_pixels(g, area);
  if (band <= 0) return edges;
  const int64_t H = g.H, W = g.W, Wq = W - 1;
  std::vector<uint8_t> in;
  if (near_only) {
    in = near_band(g, edges, band);
  } else {
    std::vector<uint8_t> edge(static_cast<size_t>(H * W), 0);
    for (int64_t p : edges) edge[p] = 1;
    in = dilate_square(edge, H, W, band);
  }
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

// Edge supports on the near side of a depth edge move `shift` pixels away from the farther neighbours, into their
// own surface, keeping their depth and footprint: the silhouette's outermost Gaussians then reach that much less far
// onto the background. Depth and colour stay the pixel centre's, read before the move.
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

// Where the farther surface continues under a silhouette: for each of `pixels` on the near side of a depth edge
// (near_side; the others are skipped), up to `layers` places one pixel apart, from `start` pixels in from its
// centre, going inwards, away from the farther neighbours. Each farther neighbour's surface is extrapolated as a
// plane to the place (or kept at its own depth where the plane would come as near as the pixel over the place); the
// place takes their mean depth and their mean colour. Layering stops where the place would not be hidden: beyond the
// image, over an invalid pixel or one not nearer than it, or (after the first) where the farther neighbours surround
// the pixel evenly, as on a line one pixel wide.
struct Behind {
  std::vector<double> u, v;
  std::vector<float> depth, color;  // colour: 3 per place
  std::vector<int64_t> from;        // the farther neighbour whose surface it continues (its normal is used)
};
Behind behind_places(const Grid& g, const std::vector<int64_t>& pixels, int64_t layers, int64_t start) {
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
    for (int64_t s = flat ? 0 : start; s < (flat ? 1 : start + layers); ++s) {
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

// The places of `b` at `indices`, in that order.
Behind select_places(const Behind& b, const std::vector<int64_t>& indices) {
  Behind out;
  for (int64_t k : indices) {
    out.u.push_back(b.u[k]), out.v.push_back(b.v[k]), out.depth.push_back(b.depth[k]), out.from.push_back(b.from[k]);
    for (int c = 0; c < 3; ++c) out.color.push_back(b.color[3 * k + c]);
  }
  return out;
}

// Writes places [0, count) of `b` as supports first.. with a pixel's footprint at their depth (they stand for
// hidden surface, so they stay out of the visible surface's area total).
void write_behind(const Grid& g, const Output& o, const Behind& b, int64_t count, int64_t first) {
  for (int64_t k = 0; k < count; ++k) {
    const int64_t t = first + k;
    o.uv[2 * t] = static_cast<float>(b.u[k]), o.uv[2 * t + 1] = static_cast<float>(b.v[k]);
    o.depth[t] = b.depth[k];
    for (int c = 0; c < 3; ++c) o.color[3 * t + c] = b.color[3 * k + c];
    o.area[t] = static_cast<float>(double(b.depth[k]) * b.depth[k] / (g.fx * g.fy));
  }
}

// Behind supports first..first+count-1 take the normal of the farther pixel they continue, not the near surface's
// at their place.
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

// `count` of the pixels, spread evenly over the list (all of them when count equals its size).
std::vector<int64_t> spread(const std::vector<int64_t>& pixels, int64_t count) {
  const int64_t size = static_cast<int64_t>(pixels.size());
  if (count >= size) return pixels;
  std::vector<int64_t> out(static_cast<size_t>(count));
  for (int64_t k = 0; k < count; ++k) out[k] = pixels[static_cast<size_t>(k * size / count)];
  return out;
}

}  // namespace

namespace {

// Per-pixel detail weights in [floor, 1] (0 where depth is unusable), see SamplerOptions.
std::vector<float> detail_weights(const Grid& g, const SamplerOptions& o) {
  const int64_t H = g.H, W = g.W, HW = H * W;
  auto ok = [&](int64_t i, int64_t j) { return i >= 0 && j >= 0 && i < H && j < W && g.valid[i * W + j] != 0.0f; };
  // Detail per pixel: the largest colour gradient (sRGB per pixel) plus the surface's curvature, measured
  // as |Laplacian of inverse depth| relative to the inverse depth (0 on any plane, large at creases and
  // depth edges).
  std::vector<float> detail(static_cast<size_t>(HW), 0.0f);
  for_each_row(H, [&](int64_t i) {
    for (int64_t j = 0; j < W; ++j) {
      if (!ok(i, j)) continue;
      const int64_t jl = ok(i, j - 1) ? j - 1 : j, jr = ok(i, j + 1) ? j + 1 : j;
      const int64_t iu = ok(i - 1, j) ? i - 1 : i, id = ok(i + 1, j) ? i + 1 : i;
      float colour = 0;
      for (int c = 0; c < 3; ++c) {
        const float* m = g.image + c * HW;
        const float gx = (m[i * W + jr] - m[i * W + jl]) / float(std::max<int64_t>(1, jr - jl));
        const float gy = (m[id * W + j] - m[iu * W + j]) / float(std::max<int64_t>(1, id - iu));
        colour = std::max(colour, std::sqrt(gx * gx + gy * gy));
      }
      const double inv = 1.0 / g.depth[i * W + j];
      double lap = 0;
      if (jl != j && jr != j) lap += 1.0 / g.depth[i * W + jl] + 1.0 / g.depth[i * W + jr] - 2 * inv;
      if (iu != i && id != i) lap += 1.0 / g.depth[iu * W + j] + 1.0 / g.depth[id * W + j] - 2 * inv;
      detail[i * W + j] = colour + static_cast<float>(std::min(1.0, std::abs(lap) / inv));
    }
  });
  // Block means over valid pixels, mapped to the weight.
  const int64_t b = o.detail_block, bh = (H + b - 1) / b, bw = (W + b - 1) / b;
  std::vector<float> weight(static_cast<size_t>(HW), 0.0f);
  at::parallel_for(0, bh, 1, [&](int64_t b0, int64_t b1) {
    for (int64_t by = b0; by < b1; ++by)
      for (int64_t bx = 0; bx < bw; ++bx) {
        double sum = 0;
        int64_t count = 0;
        for (int64_t i = by * b; i < std::min(H, (by + 1) * b); ++i)
          for (int64_t j = bx * b; j < std::min(W, (bx + 1) * b); ++j)
            if (ok(i, j)) sum += detail[i * W + j], ++count;
        if (count == 0) continue;
        const float w =
            static_cast<float>(o.detail_floor + (1.0 - o.detail_floor) * std::min(1.0, sum / count / o.detail_ref));
        for (int64_t i = by * b; i < std::min(H, (by + 1) * b); ++i)
          for (int64_t j = bx * b; j < std::min(W, (bx + 1) * b); ++j)
            if (ok(i, j)) weight[i * W + j] = w;
      }
  });
  return weight;
}

int64_t clamp_budget(const SamplerOptions& o, int64_t n) {
  return std::clamp(n, o.min_budget, std::max(o.min_budget, o.max_budget));
}

int64_t detail_budget(const SamplerOptions& o, const std::vector<float>& weight) {
  double sum = 0;
  for (float w : weight) sum += w;
  return clamp_budget(o, static_cast<int64_t>(std::llround(o.density * sum)));
}

}  // namespace

torch::Tensor detail_weights(const torch::Tensor& depth, const torch::Tensor& valid, const torch::Tensor& image,
                             const SamplerOptions& options) {
  if (options.fill_px > 0) {
    const FilledDepth f = fill_holes(depth, valid, options);
    return detail_weights(f.depth, f.valid, image, without_fill(options));
  }
  torch::Tensor dk, vk, ik;
  const Grid g = make_grid(depth, valid, torch::eye(3), image, dk, vk, ik);
  std::vector<float> w = detail_weights(g, options);
  return torch::from_blob(w.data(), {g.H, g.W}, torch::kFloat32).clone();
}

int64_t resolve_budget(const SamplerOptions& o, const torch::Tensor& depth, const torch::Tensor& valid,
                       const torch::Tensor& K, const torch::Tensor& image) {
  if (o.budget_mode == "fixed") return o.budget;
  if (o.fill_px > 0) {
    const FilledDepth f = fill_holes(depth, valid, o);
    return resolve_budget(without_fill(o), f.depth, f.valid, K, image);
  }
  if (o.budget_mode == "detail") {
    ISPLAT_CHECK(image.defined(), "sampler: budget_mode = detail needs the image");
    torch::Tensor dk, vk, ik;
    return detail_budget(o, detail_weights(make_grid(depth, valid, K, image, dk, vk, ik), o));
  }
  int64_t n = 0;
  if (o.budget_mode == "per_pixel") {
    n = static_cast<int64_t>(std::llround(o.density * depth.size(0) * depth.size(1)));
  } else if (o.budget_mode == "solid_angle") {
    // Solid angle of the valid pixels: each pixel subtends ~ cos^3(theta) / (fx fy) steradians.
    auto Kd = K.to(torch::kFloat64);
    const double fx = Kd[0][0].item<double>(), fy = Kd[1][1].item<double>(), cx = Kd[0][2].item<double>(),
                 cy = Kd[1][2].item<double>();
    const auto uv = pixel_centers(depth.size(0), depth.size(1), torch::kFloat64);
    auto x = (uv.select(-1, 0) - cx) / fx, y = (uv.select(-1, 1) - cy) / fy;
    auto cos3 = torch::pow(1.0 + x * x + y * y, -1.5);
    auto ok = usable_depth(depth, valid).to(torch::kFloat64);
    const double omega = (cos3 * ok).sum().item<double>() / (fx * fy);
    n = static_cast<int64_t>(std::llround(o.density * omega));
  } else {
    fail("sampler.budget_mode: unknown '", o.budget_mode, "'");
  }
  return clamp_budget(o, n);
}

Supports sample_supports(const torch::Tensor& depth, const torch::Tensor& valid, const torch::Tensor& K,
                         const torch::Tensor& image, const SamplerOptions& options, uint64_t seed, bool normals) {
  torch::NoGradGuard no_grad;
  if (options.fill_px > 0) {
    const FilledDepth f = fill_holes(depth, valid, options);
    return sample_supports(f.depth, f.valid, K, image, without_fill(options), seed, normals);
  }
  torch::Tensor dk, vk, ik;
  const Grid g = make_grid(depth, valid, K, image, dk, vk, ik);
  if (options.mode == "pixel") {
    std::vector<int64_t> idx;
    for (int64_t p = 0; p < g.H * g.W; ++p)
      if (g.valid[p] != 0.0f) idx.push_back(p);
    ISPLAT_CHECK(!idx.empty(), "sampler: the depth map has no valid pixel (all depth is invalid: NaN/inf/<=0)");
    Behind behind;  // pixel mode has no budget: hidden supports come on top of one support per pixel
    if (options.edge_behind > 0) behind = behind_places(g, idx, options.edge_behind, options.edge_behind_start);
    const int64_t nv = static_cast<int64_t>(idx.size()), nb = static_cast<int64_t>(behind.depth.size());
    Supports s = allocate(nv + nb);
    const Output o = pointers(s);
    write_pixel_supports(g, o, idx, nv);
    shift_edge_supports(g, o, idx, options.edge_shift);
    write_behind(g, o, behind, nb, nv);
    s.behind = nb;
    if (normals) {
      write_normals(g, s);
      behind_normals(g, s, behind, nb, nv);
    }
    return s;
  }
  std::vector<float> weight;
  if (options.budget_mode == "detail") weight = detail_weights(g, options);
  const int64_t n = weight.empty() ? resolve_budget(options, dk, vk, K) : detail_budget(options, weight);
  if (options.mode == "area") {
    Supports s = allocate(n);
    const Output o = pointers(s);
    std::vector<float> area = triangle_areas(g);
    int64_t ne = 0, nb = 0;
    double total = 0;
    for (float a : area) total += a;  // the whole surface, before a band takes triangles from the faces
    Behind behind;
    if (options.edge_supports) {
      const std::vector<int64_t> edges =
          edge_band_pixels(g, area, options.edge_band, options.edge_band_at == "near", n / 2);
      ne = std::min<int64_t>(static_cast<int64_t>(edges.size()), n / 2);  // faces keep at least half
      const std::vector<int64_t> chosen = spread(edges, ne);
      write_pixel_supports(g, o, chosen, ne);
      shift_edge_supports(g, o, chosen, options.edge_shift);
      if (options.edge_behind > 0) {  // at most half the budget with the edge supports, thinned evenly
        behind = behind_places(g, chosen, options.edge_behind, options.edge_behind_start);
        const int64_t places = static_cast<int64_t>(behind.depth.size());
        nb = std::min<int64_t>(places, n / 2 - ne);
        if (nb < places) {
          std::vector<int64_t> all(static_cast<size_t>(places));
          std::iota(all.begin(), all.end(), int64_t(0));
          behind = select_places(behind, spread(all, nb));
        }
      }
    }
    const double face_total =
        sample_faces(g, std::move(area), n - ne - nb, seed, o, ne, weight.empty() ? nullptr : weight.data(),
                     options.image_share, options.pixel_floor);
    if (ne > 0) rescale_areas(s, options.edge_band > 0 ? total : face_total, n - nb);
    write_behind(g, o, behind, nb, n - nb);
    s.behind = nb;
    if (normals) {
      write_normals(g, s);
      behind_normals(g, s, behind, nb, n - nb);
    }
    return s;
  }
  ISPLAT_CHECK(options.mode == "vertex_face", "sampler.mode: unknown '", options.mode,
               "' (area | pixel | vertex_face)");
  // Vertices: valid pixel centres with the strongest image gradients (the release's priority).
  std::vector<float> grad(static_cast<size_t>(g.H * g.W), -1.0f);
  at::parallel_for(0, g.H, 16, [&](int64_t b, int64_t e) {
    for (int64_t i = b; i < e; ++i)
      for (int64_t j = 0; j < g.W; ++j) {
        if (g.valid[i * g.W + j] == 0.0f) continue;
        float s2 = 0;
        for (int c = 0; c < 3; ++c) {
          const float* m = g.image + c * g.H * g.W;
          const float gx = m[i * g.W + std::min(j + 1, g.W - 1)] - m[i * g.W + std::max<int64_t>(j - 1, 0)];
          const float gy = m[std::min(i + 1, g.H - 1) * g.W + j] - m[std::max<int64_t>(i - 1, 0) * g.W + j];
          s2 += gx * gx + gy * gy;
        }
        grad[i * g.W + j] = s2;
      }
  });
  std::vector<int64_t> priority;
  priority.reserve(grad.size());
  for (int64_t p = 0; p < g.H * g.W; ++p)
    if (grad[p] >= 0) priority.push_back(p);
  ISPLAT_CHECK(!priority.empty(), "sampler: the depth map has no valid pixel (all depth is invalid: NaN/inf/<=0)");
  const int64_t nv = std::min<int64_t>(static_cast<int64_t>(std::llround(options.vertex_fraction * n)),
                                       static_cast<int64_t>(priority.size()));
  // The nv strongest gradients (ties by pixel index); nth_element is deterministic for equal input.
  auto stronger = [&](int64_t a, int64_t b) { return grad[a] > grad[b] || (grad[a] == grad[b] && a < b); };
  std::nth_element(priority.begin(), priority.begin() + nv, priority.end(), stronger);
  Supports s = allocate(n);
  const Output o = pointers(s);
  write_pixel_supports(g, o, priority, nv);
  rescale_areas(s, sample_faces(g, triangle_areas(g), n - nv, seed, o, nv));
  if (normals) write_normals(g, s);
  return s;
}

}  // namespace isplat
