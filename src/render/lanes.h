// Internal to the render kernels: the per-pixel forward and backward rules on a group of 8 pixels of one tile
// row, as portable scalar code (float or double) and as AVX2 + FMA intrinsics (float). Both do the same IEEE
// operations in the same order, with the same fused multiply-adds, so they give bit-identical results; the tile
// loops pick one at run time. The render sources build with -ffp-contract=off, so the compiler fuses nothing else.
#pragma once
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define ISPLAT_HAVE_AVX2_LANES 1
#include <immintrin.h>
#endif

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <type_traits>

#include "core/fast_exp.h"
#include "render/kernels.h"

#define ISPLAT_INLINE inline __attribute__((always_inline))
#define ISPLAT_AVX2 __attribute__((target("avx2,fma"), always_inline)) inline
#define ISPLAT_AVX2_FN __attribute__((target("avx2,fma")))

namespace isplat::splat {

constexpr int kPix = kTile * kTile;  // pixels per tile
constexpr int kLanes = 8;            // pixels per group

// a·b + c rounded once: the scalar twin of _mm256_fmadd_ps.
ISPLAT_INLINE float madd(float a, float b, float c) {
  return std::fma(a, b, c);
}
ISPLAT_INLINE double madd(double a, double b, double c) {
  return std::fma(a, b, c);
}

// 2^y for the splat weights, y ≤ 0. float: 2^y = 2^n · p(y − n) with n = y rounded to the nearest integer and p
// a degree-5 fit of 2^r on [−0.5, 0.5] (relative error below 2e-7); the scaling by 2^n is exact, so every lane
// width gives the same bits. double (the tests' precision): std::exp2. Forward and backward call the same one.
// The polynomial's coefficients: kExp2Poly (core/fast_exp.h), for every lane width.
constexpr float kExp2Floor = -16.0f;  // far below any cut (at most 4.5·log2 e): keeps 2^n normal
ISPLAT_INLINE float splat_exp2(float y) {
  y = std::max(y, kExp2Floor);
  const float n = std::nearbyint(y), r = y - n;  // r is exact
  float p = kExp2Poly[0];
  for (int k = 1; k < 6; ++k) p = madd(p, r, kExp2Poly[k]);
  return std::ldexp(p, int(n));
}
ISPLAT_INLINE double splat_exp2(double y) {
  return std::exp2(y);
}

// One Gaussian's constants for the pixel loops. f: the composited channels (forward: r, g, b, z, nx, ny, nz;
// backward: r, g, b, z, 1). The pixel loops work with the weight's exponent in base 2 and negated,
// −log2(e)·power, a quadratic in dx taken in Horner form: two fused multiply-adds (neg_power).
constexpr double kLog2e = 1.4426950408889634;
template <class T>
struct Splat {
  T u, v, A, B, C, opac, cut;
  T f[7];
  T beta = 0;                  // −B/A: where a row's power is smallest
  T a2 = 0, nbk = 0, nck = 0;  // −½·log2 e·A, −log2 e·B, −½·log2 e·C
  // −log2 e·cut (a pixel is in when neg_power ≥ ncut), and the same for the cut with the kSpanMargin slack
  T ncut = 0, ncut_wide = 0;
  Splat& prepare() {
    const T cut_wide = cut * T(1 + kSpanMargin) + T(kSpanMargin);
    beta = -B / A;
    a2 = T(-0.5 * kLog2e) * A, nbk = T(-kLog2e) * B, nck = T(-0.5 * kLog2e) * C;
    ncut = T(-kLog2e) * cut, ncut_wide = T(-kLog2e) * cut_wide;
    return *this;
  }
};

// Plane depth (RenderOptions::depth = "plane"): where the pixel's ray meets the plane through the mean across
// the Gaussian's shortest axis (the record's normal). Its inverse is affine in the pixel, 1/z = iz0 + gx·dx +
// gy·dy, and z is kept within kPlaneDepthRange of the mean's depth, so grazing planes stay bounded.
template <class T>
struct DepthPlane {
  T iz0 = 0, gx = 0, gy = 0, zlo = 0, izmin = 0;  // izmin = 1 / the largest depth allowed
};
template <class T>
DepthPlane<T> depth_plane(const Splat<T>& s, const CameraParams& cam) {
  const T z = s.f[3], nx = s.f[4], ny = s.f[5], nz = s.f[6];
  const T b = (s.v - T(cam.cy)) / T(cam.fy), a = (s.u - T(cam.cx) - T(cam.skew) * b) / T(cam.fx);
  const T n_dot_ray = nx * a + ny * b + nz;  // ray of the mean's pixel: (a, b, 1)
  DepthPlane<T> p;
  p.iz0 = T(1) / z, p.zlo = z / T(kPlaneDepthRange), p.izmin = T(1) / (z * T(kPlaneDepthRange));
  const T scale = std::sqrt((a * a + b * b + T(1)) * (nx * nx + ny * ny + nz * nz));
  if (!(std::abs(n_dot_ray) > T(1e-3) * scale)) return p;  // seen edge-on: the mean's depth (gx = gy = 0)
  const T k = T(1) / (z * n_dot_ray);
  p.gx = k * nx / T(cam.fx);
  p.gy = k * (ny - nx * T(cam.skew) / T(cam.fx)) / T(cam.fy);
  return p;
}
template <class T>
ISPLAT_INLINE T plane_z(const DepthPlane<T>& p, T dx, T dy) {
  return std::max(p.zlo, T(1) / std::max(madd(p.gx, dx, madd(p.gy, dy, p.iz0)), p.izmin));
}

// Per row: dy-dependent terms, computed once (after Splat::prepare). −log2 e·power = (a2·dx + nb)·dx + nc.
template <class T>
struct Row {
  T dy, nb, nc;
};
template <class T>
ISPLAT_INLINE Row<T> make_row(const Splat<T>& s, int64_t py) {
  const T dy = T(py) + T(0.5) - s.v;
  return {dy, s.nbk * dy, (s.nck * dy) * dy};
}

// −log2(e) times the exponent of the splat weight at offset dx on row r, as in avx2_neg_power.
template <class T>
ISPLAT_INLINE T neg_power(const Splat<T>& s, const Row<T>& r, T dx) {
  return madd(madd(s.a2, dx, r.nb), dx, r.nc);
}

// The dx of the first pixel of the 8-pixel group from column xb; its last is this + kLanes − 1.
template <class T>
ISPLAT_INLINE T group_dx0(const Splat<T>& s, int64_t xb) {
  return (T(xb) + T(0.5)) - s.u;
}

// Bit r − y0 set for each tile row r in [ys, ye): the rows of a Gaussian's pixel box (tile rows y0 .. y0 + 15).
ISPLAT_INLINE unsigned box_rows(int64_t y0, int64_t ys, int64_t ye) {
  return ((1u << (ye - y0)) - 1) & ~((1u << (ys - y0)) - 1);
}

// Whether the 8 pixels from column xb can pass the cut: the row's power is a convex quadratic in dx, so its
// minimum over the group's span is at beta·dy clamped to the span. Conservative by kSpanMargin; the pixel
// loops make the exact decision.
template <class T>
ISPLAT_INLINE bool group_may_hit(const Splat<T>& s, const Row<T>& r, int64_t xb) {
  const T lo = group_dx0(s, xb), hi = lo + T(kLanes - 1);
  const T dx = std::min(std::max(s.beta * r.dy, lo), hi);
  return neg_power(s, r, dx) >= s.ncut_wide;
}

// One 8-pixel group of a tile row: its row terms, the image column of lane 0 and the tile pixel index of lane 0.
template <class T>
struct Group {
  Row<T> r;
  int32_t xb, p0;
};
// The lane-sum set of a group: 0 for the left half of its tile row, 1 for the right half.
template <class T>
ISPLAT_INLINE int lane_set(const Group<T>& q) {
  return (q.p0 / kLanes) & 1;
}

// Forward state of a tile's pixels: T and 7 accumulated channels. A pixel that has stopped keeps −T
// (T > 0 always), so one plane holds both.
enum FwdPlane { kPlT = 0, kPlAcc = 1, kFwdPlanes = 8 };
// Backward planes: T, S and dL/dC for r, g, b, depth, alpha. With B_c the colour of what lies behind the
// current Gaussian (background included), S = Σ_c dL/dC_c·B_c; dL/dC is constant per pixel, so tracking S
// replaces tracking every B_c: dL/dα = T·(Σ_c dL/dC_c·f_c − S), then S ← α·Σ_c dL/dC_c·f_c + (1 − α)·S.
// The pixel loops read the first kCh of them: kBwdCh, or kBwdRgb when only colour has a gradient (training on
// colour losses), where the depth and alpha terms would add exact zeros.
constexpr int kBwdCh = 5, kBwdRgb = 3;
enum BwdPlane { kPbT = 0, kPbS = 1, kPbDC = 2, kBwdPlanes = 2 + kBwdCh };

// Index of pixel p's value in `plane`. Layout [tile row][plane][pixel of the row]: a row's state is one
// contiguous block (a plane of it is 16 floats, one AVX-512 register), and no two planes lie a multiple of
// 4 KiB apart (which makes loads wait on unrelated stores).
template <int kPlanes>
ISPLAT_INLINE int plane_at(int p, int plane) {  // p ≥ 0: unsigned, so / and % are a shift and a mask
  return int((unsigned(p) / kTile * kPlanes + unsigned(plane)) * kTile + unsigned(p) % kTile);
}
ISPLAT_INLINE int fwd_at(int p, int plane) {
  return plane_at<kFwdPlanes>(p, plane);
}
ISPLAT_INLINE int bwd_at(int p, int plane) {
  return plane_at<kBwdPlanes>(p, plane);
}

constexpr int kMaxGroups = kTile * kTile / kLanes;

// The groups of a tile whose pixels a Gaussian can still change: bit r of half[h] is row r's left (h = 0) or
// right (h = 1) group. Forward: a pixel of the group has not stopped. Backward: a pixel of the group has its
// last contributor behind the current Gaussian. A group outside the set has every lane masked off, so dropping
// it never changes a result; it only saves the work.
struct LiveGroups {
  unsigned half[2] = {0, 0};
  bool has(int64_t row, int64_t h) const { return (half[h] >> row) & 1u; }
};

// Forward: the groups with a pixel that has not stopped (T > 0 in the T plane; stopped and outside pixels hold
// a negative value).
template <class T>
ISPLAT_INLINE LiveGroups unstopped_groups(const T* st) {
  LiveGroups live;
  for (int r = 0; r < kTile; ++r)
    for (int h = 0; h < 2; ++h) {
      bool any = false;
      for (int l = 0; l < kLanes; ++l) any |= st[fwd_at(r * kTile + h * kLanes + l, kPlT)] > T(0);
      live.half[h] |= unsigned(any) << r;
    }
  return live;
}

// The bit of the group whose lane 0 is tile pixel p0 in RasterOutput::group_hits: row r's left group is bit r, its
// right group bit 16 + r.
ISPLAT_INLINE int group_bit(int p0) {
  return ((p0 & kLanes) << 1) | (p0 / kTile);
}

// Backward: per group, the largest `last` of its pixels (0 for pixels outside the image).
struct GroupLast {
  alignas(64) int32_t half[2][kTile];
  explicit GroupLast(const int32_t* last) {
    for (int r = 0; r < kTile; ++r)
      for (int h = 0; h < 2; ++h) {
        const int32_t* l = last + r * kTile + h * kLanes;
        half[h][r] = *std::max_element(l, l + kLanes);
      }
  }
  // The groups where Gaussian i (tile-local, 0-based) lies in front of some pixel's last contributor.
  LiveGroups live_for(int32_t i) const {
    LiveGroups live;
    for (int h = 0; h < 2; ++h) {
      unsigned m = 0;
      for (int r = 0; r < kTile; ++r) m |= unsigned(half[h][r] > i) << r;
      live.half[h] = m;
    }
    return live;
  }
};

// The groups of rows [ys, ye) × lane groups [g0, g1) that may be hit and are live, in row-major order (the portable
// loops'; the vector loops use avx2_tile_rows / tile_rows, which cull narrow rows too).
// Branch-free compaction (each candidate is written, the count advances only if it passes), so no
// mispredictions. `y0` is the tile's first row, so row py is bit py − y0 of `live`.
template <class T>
ISPLAT_INLINE int collect_groups(const Splat<T>& s, int64_t x0, int64_t y0, int64_t ys, int64_t ye, int64_t g0,
                                 int64_t g1, const LiveGroups& live, Group<T>* out) {
  int n = 0;
  const int32_t xb0 = int32_t(x0 + g0 * kLanes), p00 = int32_t(g0 * kLanes - y0 * kTile);
  if (g1 - g0 == 1) {  // one group per row: the box's rows are tight, so every live row is kept
    for (int64_t py = ys; py < ye; ++py) {
      out[n] = {make_row(s, py), xb0, p00 + int32_t(py * kTile)};
      n += live.has(py - y0, g0) ? 1 : 0;
    }
    return n;
  }
  for (int64_t py = ys; py < ye; ++py) {
    const Row<T> r = make_row(s, py);
    const int32_t p0 = p00 + int32_t(py * kTile);
    out[n] = {r, xb0, p0};
    n += live.has(py - y0, 0) & group_may_hit(s, r, xb0) ? 1 : 0;
    out[n] = {r, xb0 + kLanes, p0 + kLanes};
    n += live.has(py - y0, 1) & group_may_hit(s, r, xb0 + kLanes) ? 1 : 0;
  }
  return n;
}

// A Gaussian's terms of the tile's 16 rows (make_row's, computed as vectors) and which live groups it may hit
// (group_may_hit's test on all rows at once). A group the test drops has no lane within the cut, so dropping it
// or not never changes a result; nor does dropping a group that is not live (LiveGroups).
struct TileRows {
  alignas(64) float dy[kTile], nb[kTile], nc[kTile];
  unsigned groups[2];  // bit r: row r's left (0) / right (1) group is to be visited; 0 outside the box
};

// Lane sums of one Gaussian's backward: 10 quantities × 8 lanes in two sets, one per half of the tile's rows
// (lane_set; so the AVX-512 loops can run whole rows with the same sums), reduced in one fixed tree order.
template <class T>
struct LaneSums {
  T s[2][kGrad2d][kLanes];
  void reduce(T* out) const {
    auto tree = [](const T* x) { return ((x[0] + x[1]) + (x[2] + x[3])) + ((x[4] + x[5]) + (x[6] + x[7])); };
    for (int k = 0; k < kGrad2d; ++k) out[k] = tree(s[0][k]) + tree(s[1][k]);
  }
};
enum GradSlot { kGu = 0, kGv, kGA, kGB, kGC, kGo, kGr, kGg, kGb, kGz };

// The pixel loops sum moments of q = −dL/dpower = α·dL/dα in the geometry slots: Σq·dx at kGu, Σq·dy at kGv,
// Σq·dx² at kGA, Σq·dx·dy at kGB and Σq·dy² at kGC. Since power = ½(A·dx² + 2B·dx·dy + C·dy²), with dx = x − u
// and dy = y − v, the gradients follow once per Gaussian and tile (6 lane operations instead of 12):
// dL/du = A·Σq·dx + B·Σq·dy, dL/dv = B·Σq·dx + C·Σq·dy, dL/dA = −½Σq·dx², dL/dB = −Σq·dx·dy, dL/dC = −½Σq·dy².
template <class T>
ISPLAT_INLINE void moments_to_grads(const Splat<T>& s, T* out) {
  const T qx = out[kGu], qy = out[kGv], qxx = out[kGA], qxy = out[kGB], qyy = out[kGC];
  out[kGu] = madd(s.A, qx, s.B * qy), out[kGv] = madd(s.B, qx, s.C * qy);
  // 0 − x, not −x: zero sums give +0, as a slot the AVX loops fill with zeros
  out[kGA] = T(0) - T(0.5) * qxx, out[kGB] = T(0) - qxy, out[kGC] = T(0) - T(0.5) * qyy;
}

// What a forward tile loop measures besides compositing (kProbe of fwd_tile_generic and the AVX-512 loops): nothing
// (the renderer), each entry's largest weight α·T (the contribution measure), or each pixel's median depth.
enum class Probe { none, max_weight, median_depth };

// ---- Portable scalar lanes ----

// Ignores the composited pixels (the renderer's case).
struct NoSink {
  template <class T>
  ISPLAT_INLINE void operator()(int, T, T, T) const {}
};

// Front to back over the 8 pixels of group `q`. Returns how many pixels stopped here. `sink(p, w, next, z)` sees
// every composited pixel p (tile-local): its weight w = α·T, its transmittance after this Gaussian and the depth it
// composites (the contribution measure and the median depth use them; the renderer passes NoSink). A sink that
// returns bool stops the pixel when it returns true (a probe that has what it needs), leaving its sums as they were.
// The first kChannels of f are accumulated (7 with normals, 4 without, 3 without the depth too, 0 for a probe); with
// kPlane, depth is plane_z instead of f[3].
template <int kChannels, bool kPlane, class T, class Sink = NoSink>
ISPLAT_INLINE int fwd_group(const Splat<T>& s, const DepthPlane<T>& plane, const Group<T>& q, T* st, int32_t* last,
                            int32_t id, Sink&& sink = Sink{}) {
  int stops = 0;
  for (int l = 0; l < kLanes; ++l) {
    const int p = q.p0 + l;
    const T dx = (T(q.xb + l) + T(0.5)) - s.u;
    const T npow = neg_power(s, q.r, dx);
    if (!(npow >= s.ncut)) continue;  // outside 3σ, or α < 1/255 for sure: no exp
    const T raw = s.opac * splat_exp2(npow);
    const T alpha = std::min(T(kAlphaMax), raw);
    const T t = st[fwd_at(p, kPlT)], next = t * (T(1) - alpha);
    if (!(raw >= T(kAlphaMin) && t > T(0))) continue;  // skipped, or the pixel has stopped
    if (next < T(kTransmittanceMin)) {                 // this Gaussian would make the pixel opaque: stop before it
      st[fwd_at(p, kPlT)] = -t;
      ++stops;
      continue;
    }
    const T w = alpha * t;
    const T z = kPlane ? plane_z(plane, dx, q.r.dy) : s.f[3];
    if constexpr (std::is_same_v<decltype(sink(p, w, next, z)), bool>) {
      if (sink(p, w, next, z)) {
        st[fwd_at(p, kPlT)] = -next;
        ++stops;
        continue;
      }
    } else {
      sink(p, w, next, z);
    }
    for (int c = 0; c < kChannels; ++c)
      st[fwd_at(p, kPlAcc + c)] = madd(w, c == 3 ? z : s.f[c], st[fwd_at(p, kPlAcc + c)]);
    st[fwd_at(p, kPlT)] = next;
    last[p] = id;
  }
  return stops;
}

// Back to front over the 8 pixels of group `q` for Gaussian `i` (tile-local), adding to the group's lane sums.
// kCh: the gradient planes read (kBwdCh or kBwdRgb).
template <int kCh, class T>
ISPLAT_INLINE void bwd_group(const Splat<T>& s, const Group<T>& q, T* st, const int32_t* last, int32_t i,
                             LaneSums<T>& sums) {
  const Row<T>& r = q.r;
  auto& g = sums.s[lane_set(q)];
  for (int l = 0; l < kLanes; ++l) {
    const int p = q.p0 + l;
    const T dx = (T(q.xb + l) + T(0.5)) - s.u;
    const T npow = neg_power(s, r, dx);
    if (!(npow >= s.ncut) || i >= last[p]) continue;  // not a contributor in forward
    const T G = splat_exp2(npow);
    const T raw = s.opac * G;
    const T alpha = std::min(T(kAlphaMax), raw);
    if (!(raw >= T(kAlphaMin))) continue;
    const T t_in = st[bwd_at(p, kPbT)] / (T(1) - alpha);  // transmittance in front of this Gaussian
    const T w = alpha * t_in;
    T dq = st[bwd_at(p, kPbDC)] * s.f[0];  // Σ_c dL/dC_c·f_c
    for (int c = 1; c < kCh; ++c) dq = madd(st[bwd_at(p, kPbDC + c)], s.f[c], dq);
    T& S = st[bwd_at(p, kPbS)];
    const T diff = dq - S, d_alpha = diff * t_in;
    S = madd(alpha, diff, S);  // α·dq + (1 − α)·S
    st[bwd_at(p, kPbT)] = t_in;
    for (int c = 0; c < std::min(kCh, 4); ++c) g[kGr + c][l] = madd(w, st[bwd_at(p, kPbDC + c)], g[kGr + c][l]);
    if (raw > T(kAlphaMax)) continue;  // α clamped: it does not depend on the parameters
    g[kGo][l] = madd(G, d_alpha, g[kGo][l]);
    const T q = alpha * d_alpha;  // −dL/dpower; its moments, see moments_to_grads
    const T qx = q * dx, qy = q * r.dy;
    g[kGu][l] = madd(q, dx, g[kGu][l]);
    g[kGv][l] = madd(q, r.dy, g[kGv][l]);
    g[kGA][l] = madd(qx, dx, g[kGA][l]);
    g[kGB][l] = madd(qx, r.dy, g[kGB][l]);
    g[kGC][l] = madd(qy, r.dy, g[kGC][l]);
  }
}

#ifdef ISPLAT_HAVE_AVX2_LANES
// ---- AVX2 lanes (float): the same operations in the same order, N groups at a time so that their
// independent exp chains overlap. exp runs on all 8 lanes (the cut test masks the result); group culling has
// already dropped the groups that lie wholly beyond the cut ----

struct Avx2Splat {
  __m256 u, a2, opac, ncut, f[7];
};
struct Avx2Plane {
  __m256 iz0, gx, gy, zlo, izmin;
};
ISPLAT_AVX2 Avx2Plane avx2_plane(const DepthPlane<float>& p) {
  return {_mm256_set1_ps(p.iz0), _mm256_set1_ps(p.gx), _mm256_set1_ps(p.gy), _mm256_set1_ps(p.zlo),
          _mm256_set1_ps(p.izmin)};
}
ISPLAT_AVX2 Avx2Splat avx2_splat(const Splat<float>& s, int channels) {
  Avx2Splat a;
  a.u = _mm256_set1_ps(s.u), a.a2 = _mm256_set1_ps(s.a2);
  a.opac = _mm256_set1_ps(s.opac), a.ncut = _mm256_set1_ps(s.ncut);
  for (int c = 0; c < channels; ++c) a.f[c] = _mm256_set1_ps(s.f[c]);
  return a;
}

ISPLAT_AVX2 __m256 avx2_neg(__m256 x) {
  return _mm256_xor_ps(x, _mm256_set1_ps(-0.0f));
}

// splat_exp2, 8 lanes: the integer n goes straight into the exponent bits (exact, as ldexp).
ISPLAT_AVX2 __m256 avx2_exp2(__m256 y) {
  y = _mm256_max_ps(y, _mm256_set1_ps(kExp2Floor));
  const __m256 n = _mm256_round_ps(y, _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC), r = _mm256_sub_ps(y, n);
  __m256 p = _mm256_set1_ps(kExp2Poly[0]);
  for (int k = 1; k < 6; ++k) p = _mm256_fmadd_ps(p, r, _mm256_set1_ps(kExp2Poly[k]));
  const __m256i e = _mm256_slli_epi32(_mm256_cvtps_epi32(n), 23);
  return _mm256_castsi256_ps(_mm256_add_epi32(_mm256_castps_si256(p), e));
}

// dx and neg_power for the 8 lanes of group q (pixel centres xb + lane + 0.5: exact sums).
ISPLAT_AVX2 void avx2_neg_power(const Avx2Splat& a, const Group<float>& q, __m256& dx, __m256& npow) {
  const __m256 x =
      _mm256_add_ps(_mm256_set1_ps(float(q.xb)), _mm256_setr_ps(0.5f, 1.5f, 2.5f, 3.5f, 4.5f, 5.5f, 6.5f, 7.5f));
  dx = _mm256_sub_ps(x, a.u);
  npow = _mm256_fmadd_ps(_mm256_fmadd_ps(a.a2, dx, _mm256_set1_ps(q.r.nb)), dx, _mm256_set1_ps(q.r.nc));
}

template <int N, int kChannels, bool kPlane>
ISPLAT_AVX2 int fwd_groups_avx2(const Avx2Splat& a, const Avx2Plane& plane, const Group<float>* q, float* st,
                                int32_t* last, int32_t id, uint32_t& hits) {
  __m256 raw[N], npow[N], dxs[N];
  for (int k = 0; k < N; ++k) {
    avx2_neg_power(a, q[k], dxs[k], npow[k]);
    raw[k] = _mm256_mul_ps(a.opac, avx2_exp2(npow[k]));
  }
  int stops = 0;
  for (int k = 0; k < N; ++k) {
    const int p0 = q[k].p0;
    const __m256 alpha = _mm256_min_ps(raw[k], _mm256_set1_ps(float(kAlphaMax)));
    float* const base = st + fwd_at(p0, 0);  // plane k at base + k·kTile
    float* Tp = base + kPlT * kTile;
    const __m256 t = _mm256_loadu_ps(Tp);
    const __m256 next = _mm256_mul_ps(t, _mm256_sub_ps(_mm256_set1_ps(1.0f), alpha));
    const __m256 hit = _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(npow[k], a.ncut, _CMP_GE_OQ),
                                                   _mm256_cmp_ps(raw[k], _mm256_set1_ps(float(kAlphaMin)), _CMP_GE_OQ)),
                                     _mm256_cmp_ps(t, _mm256_setzero_ps(), _CMP_GT_OQ));
    const __m256 stop = _mm256_and_ps(hit, _mm256_cmp_ps(next, _mm256_set1_ps(float(kTransmittanceMin)), _CMP_LT_OQ));
    const __m256 add = _mm256_andnot_ps(stop, hit);
    const __m256 w = _mm256_and_ps(add, _mm256_mul_ps(alpha, t));
    __m256 z = _mm256_setzero_ps();  // the composited depth, read where kChannels > 3
    if constexpr (kChannels > 3) z = a.f[3];
    if constexpr (kPlane) {  // plane_z
      const __m256 iz =
          _mm256_fmadd_ps(plane.gx, dxs[k], _mm256_fmadd_ps(plane.gy, _mm256_set1_ps(q[k].r.dy), plane.iz0));
      z = _mm256_max_ps(plane.zlo, _mm256_div_ps(_mm256_set1_ps(1.0f), _mm256_max_ps(iz, plane.izmin)));
    }
    for (int c = 0; c < kChannels; ++c) {  // w = 0 where nothing is added: 0·f + acc = acc
      float* acc = base + (kPlAcc + c) * kTile;
      _mm256_storeu_ps(acc, _mm256_fmadd_ps(w, c == 3 ? z : a.f[c], _mm256_loadu_ps(acc)));
    }
    _mm256_storeu_ps(Tp, _mm256_blendv_ps(_mm256_blendv_ps(t, next, add), avx2_neg(t), stop));
    __m256i* Lp = reinterpret_cast<__m256i*>(last + p0);
    const __m256 lst = _mm256_castsi256_ps(_mm256_loadu_si256(Lp));
    _mm256_storeu_si256(Lp,
                        _mm256_castps_si256(_mm256_blendv_ps(lst, _mm256_castsi256_ps(_mm256_set1_epi32(id)), add)));
    stops += __builtin_popcount(unsigned(_mm256_movemask_ps(stop)));
    hits |= unsigned(_mm256_movemask_ps(add) != 0) << group_bit(p0);
  }
  return stops;
}

// make_row's terms of the tile's 16 rows, 8 rows per vector (the same operations per row); returns dy in `dy`.
ISPLAT_AVX2 void avx2_row_terms(const Splat<float>& s, int64_t y0, TileRows& t, __m256 dy[2]) {
  const __m256 v = _mm256_set1_ps(s.v), nbk = _mm256_set1_ps(s.nbk), nck = _mm256_set1_ps(s.nck);
  for (int h = 0; h < 2; ++h) {
    const __m256 py =  // y0 + row exactly
        _mm256_add_ps(_mm256_set1_ps(float(y0 + h * kLanes)), _mm256_setr_ps(0, 1, 2, 3, 4, 5, 6, 7));
    dy[h] = _mm256_sub_ps(_mm256_add_ps(py, _mm256_set1_ps(0.5f)), v);
    _mm256_store_ps(t.dy + h * kLanes, dy[h]);
    _mm256_store_ps(t.nb + h * kLanes, _mm256_mul_ps(nbk, dy[h]));
    _mm256_store_ps(t.nc + h * kLanes, _mm256_mul_ps(_mm256_mul_ps(nck, dy[h]), dy[h]));
  }
}
// The groups of rows [ys, ye) × lane groups [g0, g1) that may be hit and are live (collect_groups' set, with the
// culling test on every row), as TileRows::groups.
ISPLAT_AVX2 void avx2_tile_rows(const Splat<float>& s, int64_t x0, int64_t y0, int64_t ys, int64_t ye, int64_t g0,
                                int64_t g1, const LiveGroups& live, TileRows& t) {
  __m256 dy[2];
  avx2_row_terms(s, y0, t, dy);
  const unsigned rows = box_rows(y0, ys, ye);
  const __m256 beta = _mm256_set1_ps(s.beta), a2 = _mm256_set1_ps(s.a2), ncut = _mm256_set1_ps(s.ncut_wide);
  for (int g = 0; g < 2; ++g) {
    t.groups[g] = 0;
    if (g < g0 || g >= g1) continue;
    const float lo = group_dx0(s, x0 + g * kLanes), hi = lo + float(kLanes - 1);
    unsigned may = 0;
    for (int h = 0; h < 2; ++h) {
      const __m256 dx =
          _mm256_min_ps(_mm256_max_ps(_mm256_mul_ps(beta, dy[h]), _mm256_set1_ps(lo)), _mm256_set1_ps(hi));
      const __m256 q = _mm256_fmadd_ps(_mm256_fmadd_ps(a2, dx, _mm256_load_ps(t.nb + h * kLanes)), dx,
                                       _mm256_load_ps(t.nc + h * kLanes));
      may |= unsigned(_mm256_movemask_ps(_mm256_cmp_ps(q, ncut, _CMP_GE_OQ))) << (h * kLanes);
    }
    t.groups[g] = rows & live.half[g] & may;
  }
}
// The groups TileRows::groups names: the left groups in row order, then the right ones. Each lane-sum set (one per
// half) thus sees its groups in row order, as collect_groups lists them; the forward's groups touch disjoint pixels,
// so their order changes nothing there.
ISPLAT_AVX2 int avx2_groups(const TileRows& t, int64_t x0, Group<float>* out) {
  int n = 0;
  for (int h = 0; h < 2; ++h)
    for (unsigned m = t.groups[h]; m != 0; m &= m - 1) {
      const int r = __builtin_ctz(m);
      out[n++] = {{t.dy[r], t.nb[r], t.nc[r]}, int32_t(x0) + h * kLanes, r * kTile + h * kLanes};
    }
  return n;
}

// unstopped_groups on vectors: one tile row's half of the T plane per register.
ISPLAT_AVX2 LiveGroups avx2_unstopped_groups(const float* st) {
  LiveGroups live;
  for (int r = 0; r < kTile; ++r)
    for (int h = 0; h < 2; ++h) {
      const __m256 t = _mm256_loadu_ps(st + fwd_at(r * kTile + h * kLanes, kPlT));
      live.half[h] |= unsigned(_mm256_movemask_ps(_mm256_cmp_ps(t, _mm256_setzero_ps(), _CMP_GT_OQ)) != 0) << r;
    }
  return live;
}

// One set of lane sums as registers.
struct Avx2Sums {
  __m256 s[kGrad2d];
  ISPLAT_AVX2 void zero() {
    for (auto& v : s) v = _mm256_setzero_ps();
  }
};
// Per 128 bits: a0 + a1, a2 + a3, b0 + b1, b2 + b3.
ISPLAT_AVX2 __m256 pairs(__m256 a, __m256 b) {
  return _mm256_add_ps(_mm256_shuffle_ps(a, b, _MM_SHUFFLE(2, 0, 2, 0)),
                       _mm256_shuffle_ps(a, b, _MM_SHUFFLE(3, 1, 3, 1)));
}
// LaneSums::reduce of the two sets in registers, two quantities at a time: each step adds the neighbours the
// scalar tree adds (addition commutes, so every partial sum is the tree's), then the left set's total + the
// right's.
ISPLAT_AVX2 void reduce_sets(const Avx2Sums* sets, float* out) {
  for (int k = 0; k < kGrad2d; k += 2) {
    const __m256 a = pairs(sets[0].s[k], sets[1].s[k]), b = pairs(sets[0].s[k + 1], sets[1].s[k + 1]);
    const __m256 quads = pairs(a, b);  // per 128 bits: left k, right k, left k+1, right k+1 (4-sums)
    const __m128 trees = _mm_add_ps(_mm256_castps256_ps128(quads), _mm256_extractf128_ps(quads, 1));
    const __m128 totals = _mm_add_ps(trees, _mm_movehdup_ps(trees));  // left + right at 0 and 2
    out[k] = _mm_cvtss_f32(totals), out[k + 1] = _mm_cvtss_f32(_mm_movehl_ps(totals, totals));
  }
}

// Groups q[0..N), each into its lane-sum set sums[lane_set]; kCh as in bwd_group.
template <int N, int kCh>
ISPLAT_AVX2 void bwd_groups_avx2(const Avx2Splat& a, const Group<float>* q, float* st, const int32_t* last, int32_t i,
                                 Avx2Sums* sums) {
  __m256 dxs[N], npow[N], G[N];
  for (int k = 0; k < N; ++k) {
    avx2_neg_power(a, q[k], dxs[k], npow[k]);
    G[k] = avx2_exp2(npow[k]);
  }
  for (int k = 0; k < N; ++k) {
    Avx2Sums& g = sums[lane_set(q[k])];
    const int p0 = q[k].p0;
    const __m256 dx = dxs[k];
    const __m256 raw = _mm256_mul_ps(a.opac, G[k]);
    const __m256 alpha = _mm256_min_ps(raw, _mm256_set1_ps(float(kAlphaMax)));
    const __m256i lst = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(last + p0));
    const __m256 hit =
        _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(npow[k], a.ncut, _CMP_GE_OQ),
                                    _mm256_cmp_ps(raw, _mm256_set1_ps(float(kAlphaMin)), _CMP_GE_OQ)),
                      _mm256_castsi256_ps(_mm256_cmpgt_epi32(lst, _mm256_set1_epi32(i))));  // i < last[p]
    const __m256 one_minus = _mm256_sub_ps(_mm256_set1_ps(1.0f), alpha);
    float* const base = st + bwd_at(p0, 0);  // plane k at base + k·kTile
    float* Tp = base + kPbT * kTile;
    const __m256 t = _mm256_loadu_ps(Tp);
    const __m256 t_in = _mm256_div_ps(t, one_minus);
    const __m256 w = _mm256_mul_ps(alpha, t_in);
    __m256 dc[kCh];
    for (int c = 0; c < kCh; ++c) dc[c] = _mm256_loadu_ps(base + (kPbDC + c) * kTile);
    __m256 dq = _mm256_mul_ps(dc[0], a.f[0]);
    for (int c = 1; c < kCh; ++c) dq = _mm256_fmadd_ps(dc[c], a.f[c], dq);
    float* Sp = base + kPbS * kTile;
    const __m256 S = _mm256_loadu_ps(Sp);
    const __m256 diff = _mm256_sub_ps(dq, S), d_alpha = _mm256_mul_ps(diff, t_in);
    const __m256 S_new = _mm256_fmadd_ps(alpha, diff, S);
    _mm256_storeu_ps(Sp, _mm256_blendv_ps(S, S_new, hit));
    _mm256_storeu_ps(Tp, _mm256_blendv_ps(t, t_in, hit));
    // Masked lanes add exactly zero: wh and dp are 0 there, and every factor they meet is finite.
    const __m256 wh = _mm256_and_ps(hit, w);
    for (int c = 0; c < std::min(kCh, 4); ++c) g.s[kGr + c] = _mm256_fmadd_ps(wh, dc[c], g.s[kGr + c]);
    const __m256 free = _mm256_and_ps(hit, _mm256_cmp_ps(raw, _mm256_set1_ps(float(kAlphaMax)), _CMP_LE_OQ));
    g.s[kGo] = _mm256_blendv_ps(g.s[kGo], _mm256_fmadd_ps(G[k], d_alpha, g.s[kGo]), free);
    const __m256 qp = _mm256_and_ps(free, _mm256_mul_ps(alpha, d_alpha));  // −dL/dpower
    const __m256 dy = _mm256_set1_ps(q[k].r.dy), qx = _mm256_mul_ps(qp, dx), qy = _mm256_mul_ps(qp, dy);
    g.s[kGu] = _mm256_fmadd_ps(qp, dx, g.s[kGu]);  // moments, see moments_to_grads
    g.s[kGv] = _mm256_fmadd_ps(qp, dy, g.s[kGv]);
    g.s[kGA] = _mm256_fmadd_ps(qx, dx, g.s[kGA]);
    g.s[kGB] = _mm256_fmadd_ps(qx, dy, g.s[kGB]);
    g.s[kGC] = _mm256_fmadd_ps(qy, dy, g.s[kGC]);
  }
}

#endif  // ISPLAT_HAVE_AVX2_LANES

}  // namespace isplat::splat
