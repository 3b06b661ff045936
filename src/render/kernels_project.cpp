// EWA projection of 3D Gaussians to screen-space records, and its backward to means, scales, quats, opacities.
// Both run on blocks of Gaussians, one per vector lane (GCC vector extensions), compiled once per SIMD level.
// Every lane does the one-Gaussian formulas' IEEE operations in the same order (the file builds with
// -ffp-contract=off), so all levels give bit-identical records and gradients (a NaN's sign bit aside).
#include <ATen/Dispatch.h>
#include <ATen/Parallel.h>

#include <atomic>
#include <type_traits>
#include <utility>

#include "render/kernels.h"
#include "render/lanes_avx512.h"  // the target macros of the SIMD levels

namespace isplat::splat {
namespace {

// L Gaussians per block, one per lane: 256-bit vectors on AVX2 and AVX-512 (8 floats; one register on AVX2, half
// of one on AVX-512), 128-bit in the portable build (4 floats, 2 doubles). 16 float lanes took about 1.3-1.8x as
// long on AVX-512 and 2-2.8x on AVX2 (measured, lab/2026-11-27-projection-simd).
template <class T, int L>
struct VecOf {
  typedef T type __attribute__((vector_size(L * sizeof(T))));
};
template <class T, int L>
using Vec = typename VecOf<T, L>::type;
template <class T, int L>
using Mask = decltype(Vec<T, L>{} < Vec<T, L>{});  // lane-wise comparison result: −1 (true) or 0
template <class V>
constexpr int lanes_of = int(sizeof(V) / sizeof(std::declval<V>()[0]));

template <int L, class T>
ISPLAT_INLINE Vec<T, L> bcast(T x) {  // exact, −0 included
  Vec<T, L> v;
  for (int j = 0; j < L; ++j) v[j] = x;
  return v;
}
// std::min(a, b) and std::max(a, b) lane by lane, NaN handling included.
template <class V>
ISPLAT_INLINE V vmin(V a, V b) {
  return b < a ? b : a;
}
template <class V>
ISPLAT_INLINE V vmax(V a, V b) {
  return a < b ? b : a;
}
template <class V>
ISPLAT_INLINE auto finite(V x) {
  return x - x == 0;  // NaN and ±inf give NaN
}
template <class V>
ISPLAT_INLINE V vsqrt(V x) {
  for (int j = 0; j < lanes_of<V>; ++j) x[j] = std::sqrt(x[j]);
  return x;
}

// One block's inputs, transposed to one vector per component. Lanes past the end hold zero scales (culled).
template <class T, int L>
struct InputBlock {
  Vec<T, L> m[3], s[3], q[4], o;
};
template <class T, int L>
ISPLAT_INLINE void load_block(const T* means, const T* scales, const T* quats, const T* opac, int64_t first, int count,
                              InputBlock<T, L>& in) {
  for (int j = 0; j < L; ++j) {
    const bool real = j < count;
    const int64_t i = first + (real ? j : 0);
    for (int c = 0; c < 3; ++c)
      in.m[c][j] = real ? means[3 * i + c] : T(0), in.s[c][j] = real ? scales[3 * i + c] : T(0);
    for (int c = 0; c < 4; ++c) in.q[c][j] = real ? quats[4 * i + c] : T(0);
    in.o[j] = real ? opac[i] : T(0);
  }
}

// Everything the forward computes for a block that the backward needs again.
template <class T, int L>
struct GeometryBlock {
  Vec<T, L> t[3];    // camera-space mean
  Vec<T, L> a, b;    // t.x/t.z, t.y/t.z (unclamped)
  Vec<T, L> ac, bc;  // clamped into 1.3× the frustum, for the Jacobian
  Mask<T, L> u_clamped, v_clamped;
  Vec<T, L> q[4], qnorm;  // normalized quaternion, norm of the input
  Vec<T, L> Rq[9];        // rotation of the normalized quaternion, row-major
  Vec<T, L> Tm[6];        // J·W, 2×3
  Vec<T, L> M[9];         // Rq·diag(s)
  Vec<T, L> A2[6];        // Tm·M, 2×3: Σ_raw = A2·A2ᵀ
  Vec<T, L> sa, sb, sc;   // Σ_raw = [[sa, sb], [sb, sc]]
  Vec<T, L> ad, cd;       // the diagonal of Σ_raw + dilation·I
  Vec<T, L> det;          // det(Σ_raw + dilation·I)
  Vec<T, L> A, B, C;      // conic (Σ_raw + dilation·I)⁻¹ = [[A, B], [B, C]]
  Vec<T, L> rho;          // det Σ_raw / det (antialiased mode)
  Vec<T, L> opac;         // effective opacity o'
  Mask<T, L> live;        // false: culled (behind the near plane, degenerate, invisible or non-finite)
};

// J (2×3, row-major), the projection's Jacobian at depth tz and the clamped normalized point (ac, bc);
// one definition for the forward and the backward pass.
template <class T, int L>
ISPLAT_INLINE void projection_jacobian(T fx, T fy, T sk, Vec<T, L> tz, Vec<T, L> ac, Vec<T, L> bc, Vec<T, L> (&J)[6]) {
  J[0] = fx / tz, J[1] = sk / tz, J[2] = -(fx * ac + sk * bc) / tz;
  J[3] = bcast<L>(T(0)), J[4] = fy / tz, J[5] = -fy * bc / tz;
}

template <class T, int L>
ISPLAT_INLINE void project_block(const InputBlock<T, L>& in, const CameraParams& cam, const ProjectSettings& st,
                                 GeometryBlock<T, L>& g) {
  using V = Vec<T, L>;
  const double* R = cam.R;
  for (int i = 0; i < 3; ++i)
    g.t[i] = T(R[3 * i]) * in.m[0] + T(R[3 * i + 1]) * in.m[1] + T(R[3 * i + 2]) * in.m[2] + T(cam.t[i]);
  Mask<T, L> live = (g.t[2] >= T(st.near)) & (in.s[0] > T(0)) & (in.s[1] > T(0)) & (in.s[2] > T(0)) & (in.o > T(0));
  const V qn2 = in.q[0] * in.q[0] + in.q[1] * in.q[1] + in.q[2] * in.q[2] + in.q[3] * in.q[3];
  live &= (qn2 > T(1e-30)) & finite(qn2);
  g.qnorm = vsqrt(qn2);
  for (int i = 0; i < 4; ++i) g.q[i] = in.q[i] / g.qnorm;
  const V w = g.q[0], x = g.q[1], y = g.q[2], z = g.q[3];
  V* Rq = g.Rq;
  Rq[0] = T(1) - T(2) * (y * y + z * z), Rq[1] = T(2) * (x * y - w * z), Rq[2] = T(2) * (x * z + w * y);
  Rq[3] = T(2) * (x * y + w * z), Rq[4] = T(1) - T(2) * (x * x + z * z), Rq[5] = T(2) * (y * z - w * x);
  Rq[6] = T(2) * (x * z - w * y), Rq[7] = T(2) * (y * z + w * x), Rq[8] = T(1) - T(2) * (x * x + y * y);

  const T fx = T(cam.fx), fy = T(cam.fy), cx = T(cam.cx), cy = T(cam.cy), sk = T(cam.skew);
  const V tz = g.t[2];
  g.a = g.t[0] / tz, g.b = g.t[1] / tz;
  // Clamp in pixel space to [-0.15, 1.15]× the image (1.3× the frustum, as gsplat generalizes the reference
  // rasterizer to any principal point); with skew, u is clamped on the already-clamped row.
  const T mx = T(0.5 * (kFrustumClamp - 1.0) * double(cam.width));
  const T my = T(0.5 * (kFrustumClamp - 1.0) * double(cam.height));
  const T vlo = -my, vhi = T(cam.height) + my, ulo = -mx, uhi = T(cam.width) + mx;
  const T blo = (vlo - cy) / fy, bhi = (vhi - cy) / fy;
  g.v_clamped = (g.b < blo) | (g.b > bhi);
  g.bc = vmin(vmax(g.b, bcast<L>(blo)), bcast<L>(bhi));
  const V uc = fx * g.a + sk * g.bc + cx;
  g.u_clamped = (uc < ulo) | (uc > uhi);
  g.ac = g.u_clamped ? ((uc < ulo ? bcast<L>(ulo) : bcast<L>(uhi)) - cx - sk * g.bc) / fx : g.a;

  // J (2×3) at the clamped point, then Tm = J·W.
  V J[6];
  projection_jacobian<T, L>(fx, fy, sk, tz, g.ac, g.bc, J);
  for (int r = 0; r < 2; ++r)
    for (int c = 0; c < 3; ++c)
      g.Tm[3 * r + c] = J[3 * r] * T(R[c]) + J[3 * r + 1] * T(R[3 + c]) + J[3 * r + 2] * T(R[6 + c]);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) g.M[3 * r + c] = Rq[3 * r + c] * in.s[c];
  for (int r = 0; r < 2; ++r)
    for (int c = 0; c < 3; ++c)
      g.A2[3 * r + c] = g.Tm[3 * r] * g.M[c] + g.Tm[3 * r + 1] * g.M[3 + c] + g.Tm[3 * r + 2] * g.M[6 + c];
  const V* r0 = g.A2;
  const V* r1 = g.A2 + 3;
  g.sa = r0[0] * r0[0] + r0[1] * r0[1] + r0[2] * r0[2];
  g.sb = r0[0] * r1[0] + r0[1] * r1[1] + r0[2] * r1[2];
  g.sc = r1[0] * r1[0] + r1[1] * r1[1] + r1[2] * r1[2];
  const T dil = T(st.dilation);
  g.ad = g.sa + dil, g.cd = g.sc + dil;
  g.det = g.ad * g.cd - g.sb * g.sb;
  live &= (g.det > T(0)) & finite(g.det);  // degenerate 2D covariance: culled, so its lanes' quotients are unused
  g.A = g.cd / g.det, g.B = -g.sb / g.det, g.C = g.ad / g.det;
  g.rho = bcast<L>(T(1)), g.opac = in.o;
  if (st.antialiased) {
    g.rho = (g.sa * g.sc - g.sb * g.sb) / g.det;
    live &= g.rho > T(0);
    g.opac = in.o * vsqrt(g.rho);
  }
  g.live = live & (T(255) * g.opac > T(1));  // otherwise α can never reach 1/255
}

template <class T>
struct ProjectInputs {
  const T *means, *scales, *quats, *colors, *opac;
};

// Projects Gaussians [begin, end) into their records and tile rectangles; counts non-finite inputs into bad[5].
template <class T, int L>
ISPLAT_INLINE void project_fwd_range(const ProjectInputs<T>& src, int64_t begin, int64_t end, const CameraParams& cam,
                                     const ProjectSettings& st, T* packed, int32_t* rects, int64_t* bad) {
  using V = Vec<T, L>;
  const int32_t tiles_x = int32_t(cam.tiles_x()), tiles_y = int32_t(cam.tiles_y());
  const T fx = T(cam.fx), fy = T(cam.fy), cx = T(cam.cx), cy = T(cam.cy), sk = T(cam.skew);
  using D = Vec<double, L>;  // the rectangle in double, as for one Gaussian
  using I = Vec<int32_t, L>;
  // floor(x) clamped to [lo, hi] (huge or NaN x included: NaN gives lo), without a libm call.
  auto floor_clamped = [](D x, int32_t lo, int32_t hi) {
    const D c = vmin(bcast<L>(double(hi)), vmax(bcast<L>(double(lo)), x));
    const I i = __builtin_convertvector(c, I);
    return i + __builtin_convertvector(__builtin_convertvector(i, D) > c, I);  // the mask is −1 where true
  };
  InputBlock<T, L> in;
  GeometryBlock<T, L> g;
  for (int64_t first = begin; first < end; first += L) {
    const int count = int(std::min<int64_t>(L, end - first));
    load_block(src.means, src.scales, src.quats, src.opac, first, count, in);
    V col[3];
    for (int j = 0; j < L; ++j)
      for (int c = 0; c < 3; ++c) col[c][j] = j < count ? src.colors[3 * (first + j) + c] : T(0);
    // Non-finite inputs, counted per input (lanes past the end hold zeros); such a Gaussian is culled. A comparison
    // gives −1 where true, so each sum is minus the lane's count.
    auto nonfinite = [](V x) { return finite(x) == 0; };
    const Mask<T, L> per_input[5] = {nonfinite(in.m[0]) + nonfinite(in.m[1]) + nonfinite(in.m[2]),
                                     nonfinite(in.s[0]) + nonfinite(in.s[1]) + nonfinite(in.s[2]),
                                     nonfinite(in.q[0]) + nonfinite(in.q[1]) + nonfinite(in.q[2]) + nonfinite(in.q[3]),
                                     nonfinite(col[0]) + nonfinite(col[1]) + nonfinite(col[2]), nonfinite(in.o)};
    Mask<T, L> dirty = per_input[0] | per_input[1] | per_input[2] | per_input[3] | per_input[4];
    for (int k = 0; k < 5; ++k)
      for (int j = 0; j < L; ++j) bad[k] -= per_input[k][j];
    project_block(in, cam, st, g);
    const V u = fx * g.a + sk * g.b + cx, v = fy * g.b + cy;
    const Mask<T, L> live = g.live & finite(u) & finite(v) & finite(g.A) & finite(g.B) & finite(g.C) & (dirty == 0);
    const V scaled_opac = T(255) * g.opac;
    // ln(255·o') only where it may be below the cap: ln 91 > 4.5.
    V cut = bcast<L>(T(kMaxPower));
    for (int j = 0; j < count; ++j)
      if (live[j] && scaled_opac[j] < T(91)) cut[j] = std::min(T(kMaxPower), std::log(scaled_opac[j]));
    // Tile rectangle of the cut ellipse's bounding box (pixel centre c lies in tile floor(c / 16)).
    const D extent2 = 2.0 * (__builtin_convertvector(cut, D) * (1.0 + kSpanMargin) + kSpanMargin);
    const D rx = vsqrt(extent2 * __builtin_convertvector(g.ad, D)) + kSpanMargin,
            ry = vsqrt(extent2 * __builtin_convertvector(g.cd, D)) + kSpanMargin;
    const D ud = __builtin_convertvector(u, D), vd = __builtin_convertvector(v, D);
    const I tx0 = floor_clamped((ud - rx) / kTile, 0, tiles_x);
    const I tx1 = floor_clamped((ud + rx) / kTile, -1, tiles_x - 1) + 1;
    const I ty0 = floor_clamped((vd - ry) / kTile, 0, tiles_y);
    const I ty1 = floor_clamped((vd + ry) / kTile, -1, tiles_y - 1) + 1;
    // Normal: the axis of the smallest scale, in camera space, flipped to face the camera.
    const Mask<T, L> smallest_y = (in.s[1] < in.s[0]) & (in.s[1] <= in.s[2]);
    const Mask<T, L> smallest_z = (in.s[2] < in.s[0]) & (in.s[2] < in.s[1]);
    V axis[3], nrm[3];
    for (int r = 0; r < 3; ++r) axis[r] = smallest_y ? g.Rq[3 * r + 1] : smallest_z ? g.Rq[3 * r + 2] : g.Rq[3 * r];
    for (int r = 0; r < 3; ++r)
      nrm[r] = T(cam.R[3 * r]) * axis[0] + T(cam.R[3 * r + 1]) * axis[1] + T(cam.R[3 * r + 2]) * axis[2];
    const Mask<T, L> flip = nrm[0] * g.t[0] + nrm[1] * g.t[1] + nrm[2] * g.t[2] > T(0);
    for (auto& c : nrm) c = flip ? -c : c;

    for (int j = 0; j < count; ++j) {
      const int64_t i = first + j;
      T* rec = packed + i * kRec;
      int32_t* rect = rects + i * 4;
      // Culled, or the footprint misses the image: a zero record and an empty rectangle.
      if (!live[j] || tx0[j] >= tx1[j] || ty0[j] >= ty1[j]) {
        std::fill(rec, rec + kRec, T(0));
        std::fill(rect, rect + 4, 0);
        continue;
      }
      rect[0] = tx0[j], rect[1] = ty0[j], rect[2] = tx1[j], rect[3] = ty1[j];
      rec[kU] = u[j], rec[kV] = v[j], rec[kConA] = g.A[j], rec[kConB] = g.B[j], rec[kConC] = g.C[j];
      rec[kOpac] = g.opac[j], rec[kCut] = cut[j], rec[kDepth] = g.t[2][j];
      rec[kR] = col[0][j], rec[kG] = col[1][j], rec[kB] = col[2][j];
      rec[kNx] = nrm[0][j], rec[kNy] = nrm[1][j], rec[kNz] = nrm[2][j];
      rec[kRx] = T(rx[j]), rec[kRy] = T(ry[j]);
    }
  }
}

// Back-propagates the 2D gradients of Gaussians [begin, end) through the projection.
template <class T, int L>
ISPLAT_INLINE void project_bwd_range(const ProjectInputs<T>& src, int64_t begin, int64_t end, const CameraParams& cam,
                                     const ProjectSettings& st, const T* grad2d, T* g_means, T* g_scales, T* g_quats,
                                     T* g_opac) {
  using V = Vec<T, L>;
  const T fx = T(cam.fx), fy = T(cam.fy), sk = T(cam.skew);
  const double* R = cam.R;
  InputBlock<T, L> in;
  GeometryBlock<T, L> g;
  for (int64_t first = begin; first < end; first += L) {
    const int count = int(std::min<int64_t>(L, end - first));
    std::fill(g_means + 3 * first, g_means + 3 * (first + count), T(0));
    std::fill(g_scales + 3 * first, g_scales + 3 * (first + count), T(0));
    std::fill(g_quats + 4 * first, g_quats + 4 * (first + count), T(0));
    std::fill(g_opac + first, g_opac + first + count, T(0));
    V gi[kGrad2d];
    bool any_in_block = false;
    for (int j = 0; j < L; ++j)
      for (int k = 0; k < kGrad2d; ++k) {
        gi[k][j] = j < count ? grad2d[(first + j) * kGrad2d + k] : T(0);
        any_in_block |= gi[k][j] != 0;
      }
    if (!any_in_block) continue;  // culled or never contributing
    Mask<T, L> any = gi[0] != T(0);
    for (int k = 1; k < kGrad2d; ++k) any |= gi[k] != T(0);
    load_block(src.means, src.scales, src.quats, src.opac, first, count, in);
    project_block(in, cam, st, g);
    const Mask<T, L> live = g.live & any;
    const V gu = gi[0], gv = gi[1], gA = gi[2], gB = gi[3], gC = gi[4], gop = gi[5], gdepth = gi[9];

    // Opacity (and the antialiasing factor sqrt(ρ), ρ = det Σ_raw / det).
    V g_sa = bcast<L>(T(0)), g_sb = g_sa, g_sc = g_sa, g_det = g_sa, g_o;
    if (st.antialiased) {
      const V sr = vsqrt(g.rho);
      g_o = gop * sr;
      const V g_rho = gop * in.o / (T(2) * sr);
      const V g_detraw = g_rho / g.det;
      g_det -= g_rho * g.rho / g.det;
      g_sa += g_detraw * g.sc, g_sc += g_detraw * g.sa, g_sb -= T(2) * g.sb * g_detraw;
    } else {
      g_o = gop;
    }
    // Conic = (cd, -sb, ad) / det.
    g_det -= (gA * g.A + gB * g.B + gC * g.C) / g.det;
    V g_ad = gC / g.det, g_cd = gA / g.det;
    g_sb -= gB / g.det;
    g_ad += g_det * g.cd, g_cd += g_det * g.ad, g_sb -= T(2) * g.sb * g_det;
    g_sa += g_ad, g_sc += g_cd;

    // Σ_raw = A2·A2ᵀ.
    V gA2[6];
    for (int c = 0; c < 3; ++c) {
      gA2[c] = T(2) * g_sa * g.A2[c] + g_sb * g.A2[3 + c];
      gA2[3 + c] = g_sb * g.A2[c] + T(2) * g_sc * g.A2[3 + c];
    }
    // A2 = Tm·M: gTm = gA2·Mᵀ, gM = Tmᵀ·gA2.
    V gTm[6], gM[9];
    for (int r = 0; r < 2; ++r)
      for (int c = 0; c < 3; ++c)
        gTm[3 * r + c] = gA2[3 * r] * g.M[3 * c] + gA2[3 * r + 1] * g.M[3 * c + 1] + gA2[3 * r + 2] * g.M[3 * c + 2];
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) gM[3 * r + c] = g.Tm[r] * gA2[c] + g.Tm[3 + r] * gA2[3 + c];
    // M = Rq·diag(s).
    V G[9], gs[3];
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) G[3 * r + c] = gM[3 * r + c] * in.s[c];
    for (int c = 0; c < 3; ++c) gs[c] = gM[c] * g.Rq[c] + gM[3 + c] * g.Rq[3 + c] + gM[6 + c] * g.Rq[6 + c];
    // Rq(q̂), then q̂ = q / |q|.
    const V w = g.q[0], x = g.q[1], y = g.q[2], z = g.q[3];
    V gqn[4], gq[4];
    gqn[0] = T(2) * (-z * G[1] + y * G[2] + z * G[3] - x * G[5] - y * G[6] + x * G[7]);
    gqn[1] =
        T(2) * (y * G[1] + z * G[2] + y * G[3] - T(2) * x * G[4] - w * G[5] + z * G[6] + w * G[7] - T(2) * x * G[8]);
    gqn[2] =
        T(2) * (T(-2) * y * G[0] + x * G[1] + w * G[2] + x * G[3] + z * G[5] - w * G[6] + z * G[7] - T(2) * y * G[8]);
    gqn[3] =
        T(2) * (T(-2) * z * G[0] - w * G[1] + x * G[2] + w * G[3] - T(2) * z * G[4] + y * G[5] + x * G[6] + y * G[7]);
    const V dot = w * gqn[0] + x * gqn[1] + y * gqn[2] + z * gqn[3];
    for (int k = 0; k < 4; ++k) gq[k] = (gqn[k] - g.q[k] * dot) / g.qnorm;

    // Tm = J·W: gJ = gTm·Wᵀ.
    V gJ[6];
    for (int r = 0; r < 2; ++r)
      for (int c = 0; c < 3; ++c)
        gJ[3 * r + c] = gTm[3 * r] * T(R[3 * c]) + gTm[3 * r + 1] * T(R[3 * c + 1]) + gTm[3 * r + 2] * T(R[3 * c + 2]);
    const V tz = g.t[2];
    V J[6];
    projection_jacobian<T, L>(fx, fy, sk, tz, g.ac, g.bc, J);
    V g_tz = bcast<L>(T(0));
    for (int k = 0; k < 6; ++k) g_tz -= gJ[k] * J[k] / tz;  // every entry of J is ∝ 1/z
    V g_ac = -fx * gJ[2] / tz;
    V g_bc = -(sk * gJ[2] + fy * gJ[5]) / tz;
    // Through the frustum clamp: a clamped coordinate is constant in its own argument.
    g_bc = g.u_clamped ? g_bc - sk / fx * g_ac : g_bc;
    g_ac = g.u_clamped ? bcast<L>(T(0)) : g_ac;
    V g_a = g_ac, g_b = g.v_clamped ? bcast<L>(T(0)) : g_bc;
    // Mean: u = fx·a + skew·b + cx, v = fy·b + cy.
    g_a += fx * gu;
    g_b += sk * gu + fy * gv;
    const V g_t[3] = {g_a / tz, g_b / tz, g_tz + gdepth - (g_a * g.a + g_b * g.b) / tz};
    V gm[3];
    for (int c = 0; c < 3; ++c) gm[c] = T(R[c]) * g_t[0] + T(R[3 + c]) * g_t[1] + T(R[6 + c]) * g_t[2];

    for (int j = 0; j < count; ++j) {
      if (!live[j]) continue;
      const int64_t i = first + j;
      for (int c = 0; c < 3; ++c) g_means[3 * i + c] = gm[c][j], g_scales[3 * i + c] = gs[c][j];
      for (int c = 0; c < 4; ++c) g_quats[4 * i + c] = gq[c][j];
      g_opac[i] = g_o[j];
    }
  }
}

// Each range function once per SIMD level: the same source, so the same operations in every lane.
template <class T>
void project_fwd_portable(const ProjectInputs<T>& src, int64_t begin, int64_t end, const CameraParams& cam,
                          const ProjectSettings& st, T* packed, int32_t* rects, int64_t* bad) {
  project_fwd_range<T, int(16 / sizeof(T))>(src, begin, end, cam, st, packed, rects, bad);
}
template <class T>
void project_bwd_portable(const ProjectInputs<T>& src, int64_t begin, int64_t end, const CameraParams& cam,
                          const ProjectSettings& st, const T* grad2d, T* gm, T* gs, T* gq, T* go) {
  project_bwd_range<T, int(16 / sizeof(T))>(src, begin, end, cam, st, grad2d, gm, gs, gq, go);
}
#ifdef ISPLAT_HAVE_AVX2_LANES
ISPLAT_AVX2_FN void project_fwd_avx2(const ProjectInputs<float>& src, int64_t begin, int64_t end,
                                     const CameraParams& cam, const ProjectSettings& st, float* packed, int32_t* rects,
                                     int64_t* bad) {
  project_fwd_range<float, 8>(src, begin, end, cam, st, packed, rects, bad);
}
ISPLAT_AVX512_FN void project_fwd_avx512(const ProjectInputs<float>& src, int64_t begin, int64_t end,
                                         const CameraParams& cam, const ProjectSettings& st, float* packed,
                                         int32_t* rects, int64_t* bad) {
  project_fwd_range<float, 8>(src, begin, end, cam, st, packed, rects, bad);
}
ISPLAT_AVX2_FN void project_bwd_avx2(const ProjectInputs<float>& src, int64_t begin, int64_t end,
                                     const CameraParams& cam, const ProjectSettings& st, const float* grad2d, float* gm,
                                     float* gs, float* gq, float* go) {
  project_bwd_range<float, 8>(src, begin, end, cam, st, grad2d, gm, gs, gq, go);
}
ISPLAT_AVX512_FN void project_bwd_avx512(const ProjectInputs<float>& src, int64_t begin, int64_t end,
                                         const CameraParams& cam, const ProjectSettings& st, const float* grad2d,
                                         float* gm, float* gs, float* gq, float* go) {
  project_bwd_range<float, 8>(src, begin, end, cam, st, grad2d, gm, gs, gq, go);
}
#endif

template <class T>
using FwdRangeFn = void (*)(const ProjectInputs<T>&, int64_t, int64_t, const CameraParams&, const ProjectSettings&, T*,
                            int32_t*, int64_t*);
template <class T>
using BwdRangeFn = void (*)(const ProjectInputs<T>&, int64_t, int64_t, const CameraParams&, const ProjectSettings&,
                            const T*, T*, T*, T*, T*);

// The range functions for the SIMD level in use (float), else portable.
template <class T>
std::pair<FwdRangeFn<T>, BwdRangeFn<T>> range_fns() {
#ifdef ISPLAT_HAVE_AVX2_LANES
  if constexpr (std::is_same_v<T, float>) {
    if (simd_level() == Simd::avx512) return {project_fwd_avx512, project_bwd_avx512};
    if (simd_level() == Simd::avx2) return {project_fwd_avx2, project_bwd_avx2};
  }
#endif
  return {project_fwd_portable<T>, project_bwd_portable<T>};
}

// Tasks take whole multiples of the block, so only the array's last block is partial.
constexpr int64_t kGrain = 2048;
static_assert(kGrain % 16 == 0);  // a multiple of every block size (2, 4 or 8 lanes)

}  // namespace

Projection project_fwd(const torch::Tensor& means, const torch::Tensor& scales, const torch::Tensor& quats,
                       const torch::Tensor& colors, const torch::Tensor& opacities, const CameraParams& cam,
                       const ProjectSettings& settings) {
  const int64_t n = means.size(0);
  Projection out;
  out.packed = torch::empty({n, kRec}, means.options());
  out.rects = torch::empty({n, 4}, means.options().dtype(torch::kInt32));
  AT_DISPATCH_FLOATING_TYPES(means.scalar_type(), "project_fwd", [&] {
    using T = scalar_t;
    const ProjectInputs<T> x{means.data_ptr<T>(), scales.data_ptr<T>(), quats.data_ptr<T>(), colors.data_ptr<T>(),
                             opacities.data_ptr<T>()};
    const FwdRangeFn<T> fn = range_fns<T>().first;
    T* packed = out.packed.data_ptr<T>();
    int32_t* rects = out.rects.data_ptr<int32_t>();
    std::atomic<int64_t> bad[5] = {0, 0, 0, 0, 0};  // integer counts: the sum is the same in any order
    at::parallel_for(0, (n + kGrain - 1) / kGrain, 1, [&](int64_t c0, int64_t c1) {
      int64_t local_bad[5] = {0, 0, 0, 0, 0};
      fn(x, c0 * kGrain, std::min(n, c1 * kGrain), cam, settings, packed, rects, local_bad);
      for (int k = 0; k < 5; ++k) bad[k] += local_bad[k];
    });
    for (int k = 0; k < 5; ++k) out.nonfinite[k] = bad[k];
  });
  return out;
}

ProjectGrads project_bwd(const torch::Tensor& means, const torch::Tensor& scales, const torch::Tensor& quats,
                         const torch::Tensor& opacities, const CameraParams& cam, const ProjectSettings& settings,
                         const torch::Tensor& grad2d) {
  const int64_t n = means.size(0);
  ProjectGrads out{torch::empty_like(means), torch::empty_like(scales), torch::empty_like(quats),
                   torch::empty_like(opacities)};
  AT_DISPATCH_FLOATING_TYPES(means.scalar_type(), "project_bwd", [&] {
    using T = scalar_t;
    const ProjectInputs<T> x{means.data_ptr<T>(), scales.data_ptr<T>(), quats.data_ptr<T>(), nullptr,
                             opacities.data_ptr<T>()};
    const BwdRangeFn<T> fn = range_fns<T>().second;
    const T* g2 = grad2d.data_ptr<T>();
    T *gm = out.means.data_ptr<T>(), *gs = out.scales.data_ptr<T>(), *gq = out.quats.data_ptr<T>(),
      *go = out.opacities.data_ptr<T>();
    at::parallel_for(0, (n + kGrain - 1) / kGrain, 1, [&](int64_t c0, int64_t c1) {
      fn(x, c0 * kGrain, std::min(n, c1 * kGrain), cam, settings, g2, gm, gs, gq, go);
    });
  });
  return out;
}

}  // namespace isplat::splat
