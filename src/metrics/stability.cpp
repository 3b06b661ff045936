// Hole, crack and normal measures as plain loops over the pixels.
#include "metrics/stability.h"

#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "core/error.h"
#include "geometry/pixel_mask.h"

namespace isplat {
namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();

torch::Tensor plane(const torch::Tensor& t, int64_t H, int64_t W, const char* name) {
  ISPLAT_CHECK(t.defined() && t.numel() == H * W, "stability: ", name, " must be [H,W] or [1,H,W] with H x W = ", H,
               "x", W, ", got ", t.defined() ? t.sizes() : c10::IntArrayRef{});
  return t.detach().reshape({H, W}).to(torch::kFloat64).contiguous();
}

// Pixels within `margin` (Chebyshev) of a reference depth edge: a neighbour pair that jumps by >= jump·z, or
// pairs a valid with an invalid pixel. Empty when margin is 0.
std::vector<uint8_t> near_reference_edge(const double* ref, int64_t H, int64_t W, double jump, int64_t margin) {
  if (margin <= 0) return {};
  auto ok = [&](int64_t p) { return std::isfinite(ref[p]) && ref[p] > 0; };
  std::vector<uint8_t> edge(static_cast<size_t>(H * W), 0);
  for (int64_t i = 0; i < H; ++i)
    for (int64_t j = 0; j < W; ++j) {
      const int64_t p = i * W + j;
      for (const int64_t q : {j + 1 < W ? p + 1 : -1, i + 1 < H ? p + W : -1}) {
        if (q < 0) continue;
        if (ok(p) != ok(q) || (ok(p) && std::abs(ref[p] - ref[q]) >= jump * 0.5 * (ref[p] + ref[q])))
          edge[p] = edge[q] = 1;
      }
    }
  return dilate_square(edge, H, W, margin);
}

}  // namespace

double hole_rate(const torch::Tensor& alpha, const torch::Tensor& mask, const StabilityOptions& o) {
  ISPLAT_CHECK(mask.dim() == 2, "hole_rate: mask must be [H,W], got ", mask.sizes());
  const int64_t H = mask.size(0), W = mask.size(1);
  const auto a = plane(alpha, H, W, "alpha"), m = plane(mask, H, W, "mask");
  const double *pa = a.data_ptr<double>(), *pm = m.data_ptr<double>();
  int64_t in = 0, holes = 0;
  for (int64_t p = 0; p < H * W; ++p)
    if (pm[p] != 0) ++in, holes += pa[p] < o.hole_alpha;
  return in ? static_cast<double>(holes) / static_cast<double>(in) : kNaN;
}

EdgeSide parse_edge_side(const std::string& name) {
  if (name == "any") return EdgeSide::any;
  if (name == "near") return EdgeSide::near;
  ISPLAT_CHECK(name == "far", "edge side: unknown '", name, "' (any | near | far)");
  return EdgeSide::far;
}

CrackSide parse_crack_side(const std::string& name) {
  if (name == "any") return CrackSide::any;
  if (name == "nearer") return CrackSide::nearer;
  ISPLAT_CHECK(name == "farther", "crack side: unknown '", name, "' (any | nearer | farther)");
  return CrackSide::farther;
}

namespace {

// The neighbour pairs crack_rate scores, each with its verdict: fn(p, q, broken, deviant, nearer), where a broken
// pair's deviant pixel is the one whose rendered depth errs more against the reference (a hole, with holes_break),
// and nearer says which way it errs. Returns the number of pairs scored.
template <class Fn>
int64_t for_each_scored_pair(const torch::Tensor& depth_sum, const torch::Tensor& alpha, const torch::Tensor& ref_depth,
                             const torch::Tensor& mask, const StabilityOptions& o, const char* who, Fn&& fn) {
  ISPLAT_CHECK(mask.dim() == 2, who, ": mask must be [H,W], got ", mask.sizes());
  const int64_t H = mask.size(0), W = mask.size(1);
  const auto ds = plane(depth_sum, H, W, "depth"), a = plane(alpha, H, W, "alpha");
  const auto r = plane(ref_depth, H, W, "reference depth"), m = plane(mask, H, W, "mask");
  const double *pd = ds.data_ptr<double>(), *pa = a.data_ptr<double>(), *pr = r.data_ptr<double>(),
               *pm = m.data_ptr<double>();
  auto hole = [&](int64_t p) { return pa[p] < o.hole_alpha; };
  // A pixel takes part if it is masked with valid reference depth, and (unless holes break pairs) is no hole.
  auto counted = [&](int64_t p) {
    return pm[p] != 0 && std::isfinite(pr[p]) && pr[p] > 0 && (o.holes_break || !hole(p));
  };
  const std::vector<uint8_t> near_edge = near_reference_edge(pr, H, W, o.crack_jump, o.edge_margin);
  // Whether pixel d lies on edge_side of a reference depth edge within kEdgeSideReach px.
  constexpr int64_t kEdgeSideReach = 2;
  auto on_edge_side = [&](int64_t d) {
    if (o.edge_side == EdgeSide::any) return true;
    const int64_t di = d / W, dj = d % W;
    double lo = std::numeric_limits<double>::infinity(), hi = 0;
    for (int64_t y = std::max<int64_t>(di - kEdgeSideReach, 0); y <= std::min(di + kEdgeSideReach, H - 1); ++y)
      for (int64_t x = std::max<int64_t>(dj - kEdgeSideReach, 0); x <= std::min(dj + kEdgeSideReach, W - 1); ++x) {
        const double z = pr[y * W + x];
        if (std::isfinite(z) && z > 0) lo = std::min(lo, z), hi = std::max(hi, z);
      }
    if (!(hi >= lo * (1 + o.crack_jump))) return false;  // no edge that close
    return (pr[d] < std::sqrt(lo * hi)) == (o.edge_side == EdgeSide::near);
  };
  int64_t pairs = 0;
  for (int64_t i = 0; i < H; ++i)
    for (int64_t j = 0; j < W; ++j) {
      const int64_t p = i * W + j;
      if (!counted(p)) continue;
      for (const int64_t q : {j + 1 < W ? p + 1 : -1, i + 1 < H ? p + W : -1}) {
        if (q < 0 || !counted(q)) continue;
        const double zr = 0.5 * (pr[p] + pr[q]);
        if (std::abs(pr[p] - pr[q]) >= o.smooth_jump * zr) continue;  // the reference itself has an edge
        if (!near_edge.empty() && (near_edge[p] || near_edge[q])) continue;
        ++pairs;
        if (hole(p) || hole(q)) {  // only reached with holes_break; nothing drawn errs farther
          const int64_t d = hole(p) ? p : q;
          fn(p, q, on_edge_side(d), d, false);
          continue;
        }
        const double zp = pd[p] / pa[p], zq = pd[q] / pa[q];
        const double ep = zp / pr[p] - 1, eq = zq / pr[q] - 1;
        const bool p_deviates = std::abs(ep) >= std::abs(eq);
        const double error = p_deviates ? ep : eq;
        const int64_t d = p_deviates ? p : q;
        const bool broken =
            std::abs(zp - zq) > o.crack_jump * 0.5 * (zp + zq) && std::abs(error) >= o.min_error && on_edge_side(d);
        fn(p, q, broken, d, error < 0);
      }
    }
  return pairs;
}

bool counts_side(const StabilityOptions& o, bool nearer) {
  return o.crack_side == CrackSide::any || nearer == (o.crack_side == CrackSide::nearer);
}

}  // namespace

double crack_rate(const torch::Tensor& depth_sum, const torch::Tensor& alpha, const torch::Tensor& ref_depth,
                  const torch::Tensor& mask, const StabilityOptions& o) {
  int64_t cracks = 0;
  const int64_t pairs = for_each_scored_pair(
      depth_sum, alpha, ref_depth, mask, o, "crack_rate",
      [&](int64_t, int64_t, bool broken, int64_t, bool nearer) { cracks += broken && counts_side(o, nearer); });
  return pairs ? static_cast<double>(cracks) / static_cast<double>(pairs) : kNaN;
}

torch::Tensor crack_map(const torch::Tensor& depth_sum, const torch::Tensor& alpha, const torch::Tensor& ref_depth,
                        const torch::Tensor& mask, const StabilityOptions& o) {
  ISPLAT_CHECK(mask.dim() == 2, "crack_map: mask must be [H,W], got ", mask.sizes());
  const int64_t H = mask.size(0), W = mask.size(1), HW = H * W;
  auto map = torch::zeros({3, H, W}, torch::kFloat32);
  float* px = map.data_ptr<float>();
  auto paint = [&](int64_t p, float r, float g, float b) { px[p] = r, px[HW + p] = g, px[2 * HW + p] = b; };
  std::vector<uint8_t> deviant(static_cast<size_t>(HW), 0);  // 1 nearer, 2 farther
  for_each_scored_pair(depth_sum, alpha, ref_depth, mask, o, "crack_map",
                       [&](int64_t p, int64_t q, bool broken, int64_t d, bool nearer) {
                         for (int64_t k : {p, q})
                           if (px[k] == 0) paint(k, 0.3f, 0.3f, 0.3f);
                         if (broken && counts_side(o, nearer)) deviant[size_t(d)] |= nearer ? 1 : 2;
                       });
  for (int64_t p = 0; p < HW; ++p) {
    if (deviant[size_t(p)] & 2)
      paint(p, 1.0f, 0.15f, 0.1f);  // farther: a surface seen through
    else if (deviant[size_t(p)] & 1)
      paint(p, 0.2f, 0.5f, 1.0f);  // nearer: a fringe drawn over it
  }
  return map;
}

double normal_incoherence_deg(const torch::Tensor& normal_sum, const torch::Tensor& alpha,
                              const torch::Tensor& ref_depth, const torch::Tensor& K, const torch::Tensor& mask,
                              const StabilityOptions& o) {
  ISPLAT_CHECK(mask.dim() == 2, "normal_incoherence: mask must be [H,W], got ", mask.sizes());
  const int64_t H = mask.size(0), W = mask.size(1), HW = H * W;
  ISPLAT_CHECK(normal_sum.defined() && normal_sum.numel() == 3 * HW, "normal_incoherence: normals must be [3,", H, ",",
               W, "]");
  ISPLAT_CHECK(K.defined() && K.numel() == 9, "normal_incoherence: K must be [3,3]");
  const auto n = normal_sum.detach().reshape({3, HW}).to(torch::kFloat64).contiguous();
  const auto a = plane(alpha, H, W, "alpha"), r = plane(ref_depth, H, W, "reference depth"),
             m = plane(mask, H, W, "mask");
  const auto k = K.detach().to(torch::kFloat64).contiguous();
  const double *pn = n.data_ptr<double>(), *pa = a.data_ptr<double>(), *pr = r.data_ptr<double>(),
               *pm = m.data_ptr<double>(), *pk = k.data_ptr<double>();
  const double fx = pk[0], fy = pk[4], cx = pk[2], cy = pk[5];
  auto ok = [&](int64_t i, int64_t j) {
    const double z = pr[i * W + j];
    return std::isfinite(z) && z > 0;
  };
  // Reference normals from forward differences of the back-projected depth (0 where undefined).
  std::vector<double> rn(static_cast<size_t>(3 * HW), 0.0);
  auto point = [&](int64_t i, int64_t j, double* P) {
    const double z = pr[i * W + j];
    P[0] = (j + 0.5 - cx) / fx * z, P[1] = (i + 0.5 - cy) / fy * z, P[2] = z;
  };
  for (int64_t i = 0; i + 1 < H; ++i)
    for (int64_t j = 0; j + 1 < W; ++j) {
      if (!ok(i, j) || !ok(i, j + 1) || !ok(i + 1, j)) continue;
      double P[3], R[3], D[3];
      point(i, j, P), point(i, j + 1, R), point(i + 1, j, D);
      const double u[3] = {R[0] - P[0], R[1] - P[1], R[2] - P[2]}, v[3] = {D[0] - P[0], D[1] - P[1], D[2] - P[2]};
      double c[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
      const double len = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
      if (len <= 0) continue;
      for (int d = 0; d < 3; ++d) rn[static_cast<size_t>(3 * (i * W + j) + d)] = c[d] / len;
    }
  auto angle = [](const double* x, const double* y) {  // unit vectors
    const double d = std::clamp(x[0] * y[0] + x[1] * y[1] + x[2] * y[2], -1.0, 1.0);
    return std::acos(d) * 180.0 / M_PI;
  };
  auto rendered = [&](int64_t p, double* out) {
    const double x = pn[p], y = pn[HW + p], z = pn[2 * HW + p], len = std::sqrt(x * x + y * y + z * z);
    if (len <= 1e-12) return false;
    out[0] = x / len, out[1] = y / len, out[2] = z / len;
    return true;
  };
  double sum = 0;
  int64_t count = 0;
  for (int64_t i = 0; i < H; ++i)
    for (int64_t j = 0; j < W; ++j) {
      const int64_t p = i * W + j;
      const double* rp = &rn[static_cast<size_t>(3 * p)];
      if (pm[p] == 0 || pa[p] < o.hole_alpha || (rp[0] == 0 && rp[1] == 0 && rp[2] == 0)) continue;
      double np[3];
      if (!rendered(p, np)) continue;
      for (const int64_t q : {j + 1 < W ? p + 1 : -1, i + 1 < H ? p + W : -1}) {
        if (q < 0 || pm[q] == 0 || pa[q] < o.hole_alpha) continue;
        const double* rq = &rn[static_cast<size_t>(3 * q)];
        if ((rq[0] == 0 && rq[1] == 0 && rq[2] == 0) || angle(rp, rq) > o.planar_deg) continue;
        double nq[3];
        if (!rendered(q, nq)) continue;
        sum += angle(np, nq), ++count;
      }
    }
  return count ? sum / static_cast<double>(count) : kNaN;
}

}  // namespace isplat
