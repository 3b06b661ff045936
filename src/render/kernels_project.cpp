// EWA projection of 3D Gaussians to screen-space records, and its backward to means, scales, quats, opacities.
#include <ATen/Dispatch.h>
#include <ATen/Parallel.h>

#include <atomic>

#include "render/kernels.h"

namespace isplat::splat {
namespace {

// Everything the forward computes for one Gaussian that the backward needs again.
template <class T>
struct Geometry {
  T t[3];    // camera-space mean
  T a, b;    // t.x/t.z, t.y/t.z (unclamped)
  T ac, bc;  // clamped into 1.3× the frustum, for the Jacobian
  bool u_clamped, v_clamped;
  T q[4], qnorm;  // normalized quaternion, norm of the input
  T Rq[9];        // rotation of the normalized quaternion, row-major
  T Tm[6];        // J·W, 2×3
  T M[9];         // Rq·diag(s)
  T A2[6];        // Tm·M, 2×3: Σ_raw = A2·A2ᵀ
  T sa, sb, sc;   // Σ_raw = [[sa, sb], [sb, sc]]
  T det;          // det(Σ_raw + dilation·I)
  T rho;          // det Σ_raw / det (antialiased mode)
  T opac;         // effective opacity o'
};

// J (2×3, row-major), the projection's Jacobian at depth tz and the clamped normalized point (ac, bc);
// one definition for the forward and the backward pass.
template <class T>
inline void projection_jacobian(T fx, T fy, T sk, T tz, T ac, T bc, T (&J)[6]) {
  J[0] = fx / tz, J[1] = sk / tz, J[2] = -(fx * ac + sk * bc) / tz;
  J[3] = 0, J[4] = fy / tz, J[5] = -fy * bc / tz;
}

// Returns false when the Gaussian is culled (behind the near plane, degenerate, invisible or non-finite).
template <class T>
bool project_one(const T* m, const T* s, const T* qin, T o, const CameraParams& cam, const ProjectSettings& st,
                 Geometry<T>& g) {
  const double* R = cam.R;
  for (int i = 0; i < 3; ++i)
    g.t[i] = T(R[3 * i]) * m[0] + T(R[3 * i + 1]) * m[1] + T(R[3 * i + 2]) * m[2] + T(cam.t[i]);
  if (!(g.t[2] >= T(st.near))) return false;
  if (!(s[0] > 0 && s[1] > 0 && s[2] > 0) || !(o > 0)) return false;
  const T qn2 = qin[0] * qin[0] + qin[1] * qin[1] + qin[2] * qin[2] + qin[3] * qin[3];
  if (!(qn2 > T(1e-30)) || !std::isfinite(qn2)) return false;
  g.qnorm = std::sqrt(qn2);
  for (int i = 0; i < 4; ++i) g.q[i] = qin[i] / g.qnorm;
  const T w = g.q[0], x = g.q[1], y = g.q[2], z = g.q[3];
  T* Rq = g.Rq;
  Rq[0] = 1 - 2 * (y * y + z * z), Rq[1] = 2 * (x * y - w * z), Rq[2] = 2 * (x * z + w * y);
  Rq[3] = 2 * (x * y + w * z), Rq[4] = 1 - 2 * (x * x + z * z), Rq[5] = 2 * (y * z - w * x);
  Rq[6] = 2 * (x * z - w * y), Rq[7] = 2 * (y * z + w * x), Rq[8] = 1 - 2 * (x * x + y * y);

  const T fx = T(cam.fx), fy = T(cam.fy), cx = T(cam.cx), cy = T(cam.cy), sk = T(cam.skew);
  const T tz = g.t[2];
  g.a = g.t[0] / tz, g.b = g.t[1] / tz;
  // Clamp in pixel space to [-0.15, 1.15]× the image (1.3× the frustum, as gsplat generalizes the reference
  // rasterizer to any principal point); with skew, u is clamped on the already-clamped row.
  const T mx = T(0.5 * (kFrustumClamp - 1.0) * double(cam.width));
  const T my = T(0.5 * (kFrustumClamp - 1.0) * double(cam.height));
  const T vlo = -my, vhi = T(cam.height) + my, ulo = -mx, uhi = T(cam.width) + mx;
  const T blo = (vlo - cy) / fy, bhi = (vhi - cy) / fy;
  g.v_clamped = g.b < blo || g.b > bhi;
  g.bc = std::min(std::max(g.b, blo), bhi);
  const T uc = fx * g.a + sk * g.bc + cx;
  g.u_clamped = uc < ulo || uc > uhi;
  g.ac = g.u_clamped ? ((uc < ulo ? ulo : uhi) - cx - sk * g.bc) / fx : g.a;

  // J (2×3) at the clamped point, then Tm = J·W.
  T J[6];
  projection_jacobian(fx, fy, sk, tz, g.ac, g.bc, J);
  for (int r = 0; r < 2; ++r)
    for (int c = 0; c < 3; ++c)
      g.Tm[3 * r + c] = J[3 * r] * T(R[c]) + J[3 * r + 1] * T(R[3 + c]) + J[3 * r + 2] * T(R[6 + c]);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) g.M[3 * r + c] = Rq[3 * r + c] * s[c];
  for (int r = 0; r < 2; ++r)
    for (int c = 0; c < 3; ++c)
      g.A2[3 * r + c] = g.Tm[3 * r] * g.M[c] + g.Tm[3 * r + 1] * g.M[3 + c] + g.Tm[3 * r + 2] * g.M[6 + c];
  const T* r0 = g.A2;
  const T* r1 = g.A2 + 3;
  g.sa = r0[0] * r0[0] + r0[1] * r0[1] + r0[2] * r0[2];
  g.sb = r0[0] * r1[0] + r0[1] * r1[1] + r0[2] * r1[2];
  g.sc = r1[0] * r1[0] + r1[1] * r1[1] + r1[2] * r1[2];
  const T dil = T(st.dilation);
  g.det = (g.sa + dil) * (g.sc + dil) - g.sb * g.sb;
  if (!(g.det > 0) || !std::isfinite(g.det)) return false;  // degenerate 2D covariance: never divide by it
  g.rho = 1, g.opac = o;
  if (st.antialiased) {
    g.rho = (g.sa * g.sc - g.sb * g.sb) / g.det;
    if (!(g.rho > 0)) return false;
    g.opac = o * std::sqrt(g.rho);
  }
  return T(255) * g.opac > 1;  // otherwise α can never reach 1/255
}

// floor(x) clamped to [lo, hi] (huge or NaN x included), without a libm call.
inline int32_t tile_floor(double x, int32_t lo, int32_t hi) {
  const double c = std::min(double(hi), std::max(double(lo), x));
  const int32_t i = int32_t(c);
  return i - (double(i) > c);
}

template <class T>
void project_fwd_impl(const T* means, const T* scales, const T* quats, const T* colors, const T* opac, int64_t n,
                      const CameraParams& cam, const ProjectSettings& st, T* packed, int32_t* rects,
                      int64_t* nonfinite) {
  const double fx = cam.fx, fy = cam.fy, cx = cam.cx, cy = cam.cy, sk = cam.skew;
  const int32_t tiles_x = int32_t(cam.tiles_x()), tiles_y = int32_t(cam.tiles_y());
  std::atomic<int64_t> bad[5] = {0, 0, 0, 0, 0};  // integer counts: the sum is the same in any order
  at::parallel_for(0, n, 2048, [&](int64_t begin, int64_t end) {
    Geometry<T> g;
    int64_t local_bad[5] = {0, 0, 0, 0, 0};
    auto count_bad = [](const T* x, int k) {
      int b = 0;
      for (int j = 0; j < k; ++j) b += std::isfinite(x[j]) ? 0 : 1;
      return b;
    };
    for (int64_t i = begin; i < end; ++i) {
      T* rec = packed + i * kRec;
      int32_t* rect = rects + i * 4;
      std::fill(rec, rec + kRec, T(0));
      std::fill(rect, rect + 4, 0);
      const int b[5] = {count_bad(means + 3 * i, 3), count_bad(scales + 3 * i, 3), count_bad(quats + 4 * i, 4),
                        count_bad(colors + 3 * i, 3), count_bad(opac + i, 1)};
      if (b[0] + b[1] + b[2] + b[3] + b[4] > 0) {
        for (int k = 0; k < 5; ++k) local_bad[k] += b[k];
        continue;
      }
      if (!project_one(means + 3 * i, scales + 3 * i, quats + 4 * i, opac[i], cam, st, g)) continue;
      const T u = T(fx) * g.a + T(sk) * g.b + T(cx), v = T(fy) * g.b + T(cy);
      const T dil = T(st.dilation), ad = g.sa + dil, cd = g.sc + dil;
      const T A = cd / g.det, B = -g.sb / g.det, C = ad / g.det;
      const T cut = std::min(T(kMaxPower), std::log(T(255) * g.opac));
      if (!std::isfinite(u) || !std::isfinite(v) || !std::isfinite(A) || !std::isfinite(B) || !std::isfinite(C))
        continue;
      // Tile rectangle of the cut ellipse's bounding box (pixel centre c lies in tile floor(c / 16)).
      const double k2 = 2.0 * (double(cut) * (1.0 + kSpanMargin) + kSpanMargin);
      const double rx = std::sqrt(k2 * double(ad)) + kSpanMargin, ry = std::sqrt(k2 * double(cd)) + kSpanMargin;
      const int32_t tx0 = tile_floor((double(u) - rx) / kTile, 0, tiles_x);
      const int32_t tx1 = tile_floor((double(u) + rx) / kTile, -1, tiles_x - 1) + 1;
      const int32_t ty0 = tile_floor((double(v) - ry) / kTile, 0, tiles_y);
      const int32_t ty1 = tile_floor((double(v) + ry) / kTile, -1, tiles_y - 1) + 1;
      if (tx0 >= tx1 || ty0 >= ty1) continue;  // footprint misses the image
      rect[0] = tx0, rect[1] = ty0, rect[2] = tx1, rect[3] = ty1;

      // Normal: the axis of the smallest scale, in camera space, flipped to face the camera.
      const T* s = scales + 3 * i;
      const int k = (s[1] < s[0] && s[1] <= s[2]) ? 1 : (s[2] < s[0] && s[2] < s[1]) ? 2 : 0;
      T nrm[3];
      for (int r = 0; r < 3; ++r)
        nrm[r] = T(cam.R[3 * r]) * g.Rq[k] + T(cam.R[3 * r + 1]) * g.Rq[3 + k] + T(cam.R[3 * r + 2]) * g.Rq[6 + k];
      if (nrm[0] * g.t[0] + nrm[1] * g.t[1] + nrm[2] * g.t[2] > 0)
        for (auto& c : nrm) c = -c;

      rec[kU] = u, rec[kV] = v, rec[kConA] = A, rec[kConB] = B, rec[kConC] = C;
      rec[kOpac] = g.opac, rec[kCut] = cut, rec[kDepth] = g.t[2];
      rec[kR] = colors[3 * i], rec[kG] = colors[3 * i + 1], rec[kB] = colors[3 * i + 2];
      rec[kNx] = nrm[0], rec[kNy] = nrm[1], rec[kNz] = nrm[2];
      rec[kRx] = T(rx), rec[kRy] = T(ry);
    }
    for (int k = 0; k < 5; ++k) bad[k] += local_bad[k];
  });
  for (int k = 0; k < 5; ++k) nonfinite[k] = bad[k];
}

template <class T>
void project_bwd_impl(const T* means, const T* scales, const T* quats, const T* opac, int64_t n,
                      const CameraParams& cam, const ProjectSettings& st, const T* grad2d, T* g_means, T* g_scales,
                      T* g_quats, T* g_opac) {
  const T fx = T(cam.fx), fy = T(cam.fy), sk = T(cam.skew);
  const double* R = cam.R;
  at::parallel_for(0, n, 2048, [&](int64_t begin, int64_t end) {
    Geometry<T> g;
    for (int64_t i = begin; i < end; ++i) {
      const T* gi = grad2d + i * kGrad2d;
      T* gm = g_means + 3 * i;
      T* gs = g_scales + 3 * i;
      T* gq = g_quats + 4 * i;
      std::fill(gm, gm + 3, T(0));
      std::fill(gs, gs + 3, T(0));
      std::fill(gq, gq + 4, T(0));
      g_opac[i] = 0;
      bool any = false;
      for (int k = 0; k < kGrad2d; ++k) any |= gi[k] != 0;
      if (!any) continue;  // culled or never contributing
      const T* s = scales + 3 * i;
      if (!project_one(means + 3 * i, s, quats + 4 * i, opac[i], cam, st, g)) continue;
      const T gu = gi[0], gv = gi[1], gA = gi[2], gB = gi[3], gC = gi[4], gop = gi[5], gdepth = gi[9];
      const T dil = T(st.dilation), ad = g.sa + dil, cd = g.sc + dil;
      const T A = cd / g.det, B = -g.sb / g.det, C = ad / g.det;

      // Opacity (and the antialiasing factor sqrt(ρ), ρ = det Σ_raw / det).
      T g_sa = 0, g_sb = 0, g_sc = 0, g_det = 0;
      if (st.antialiased) {
        const T sr = std::sqrt(g.rho);
        g_opac[i] = gop * sr;
        const T g_rho = gop * opac[i] / (2 * sr);
        const T g_detraw = g_rho / g.det;
        g_det -= g_rho * g.rho / g.det;
        g_sa += g_detraw * g.sc, g_sc += g_detraw * g.sa, g_sb -= 2 * g.sb * g_detraw;
      } else {
        g_opac[i] = gop;
      }
      // Conic = (cd, -sb, ad) / det.
      g_det -= (gA * A + gB * B + gC * C) / g.det;
      T g_ad = gC / g.det, g_cd = gA / g.det;
      g_sb -= gB / g.det;
      g_ad += g_det * cd, g_cd += g_det * ad, g_sb -= 2 * g.sb * g_det;
      g_sa += g_ad, g_sc += g_cd;

      // Σ_raw = A2·A2ᵀ.
      T gA2[6];
      for (int c = 0; c < 3; ++c) {
        gA2[c] = 2 * g_sa * g.A2[c] + g_sb * g.A2[3 + c];
        gA2[3 + c] = g_sb * g.A2[c] + 2 * g_sc * g.A2[3 + c];
      }
      // A2 = Tm·M: gTm = gA2·Mᵀ, gM = Tmᵀ·gA2.
      T gTm[6], gM[9];
      for (int r = 0; r < 2; ++r)
        for (int c = 0; c < 3; ++c)
          gTm[3 * r + c] = gA2[3 * r] * g.M[3 * c] + gA2[3 * r + 1] * g.M[3 * c + 1] + gA2[3 * r + 2] * g.M[3 * c + 2];
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) gM[3 * r + c] = g.Tm[r] * gA2[c] + g.Tm[3 + r] * gA2[3 + c];
      // M = Rq·diag(s).
      T G[9];
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) G[3 * r + c] = gM[3 * r + c] * s[c];
      for (int c = 0; c < 3; ++c) gs[c] = gM[c] * g.Rq[c] + gM[3 + c] * g.Rq[3 + c] + gM[6 + c] * g.Rq[6 + c];
      // Rq(q̂), then q̂ = q / |q|.
      const T w = g.q[0], x = g.q[1], y = g.q[2], z = g.q[3];
      T gqn[4];
      gqn[0] = 2 * (-z * G[1] + y * G[2] + z * G[3] - x * G[5] - y * G[6] + x * G[7]);
      gqn[1] = 2 * (y * G[1] + z * G[2] + y * G[3] - 2 * x * G[4] - w * G[5] + z * G[6] + w * G[7] - 2 * x * G[8]);
      gqn[2] = 2 * (-2 * y * G[0] + x * G[1] + w * G[2] + x * G[3] + z * G[5] - w * G[6] + z * G[7] - 2 * y * G[8]);
      gqn[3] = 2 * (-2 * z * G[0] - w * G[1] + x * G[2] + w * G[3] - 2 * z * G[4] + y * G[5] + x * G[6] + y * G[7]);
      const T dot = w * gqn[0] + x * gqn[1] + y * gqn[2] + z * gqn[3];
      for (int k = 0; k < 4; ++k) gq[k] = (gqn[k] - g.q[k] * dot) / g.qnorm;

      // Tm = J·W: gJ = gTm·Wᵀ.
      T gJ[6];
      for (int r = 0; r < 2; ++r)
        for (int c = 0; c < 3; ++c)
          gJ[3 * r + c] =
              gTm[3 * r] * T(R[3 * c]) + gTm[3 * r + 1] * T(R[3 * c + 1]) + gTm[3 * r + 2] * T(R[3 * c + 2]);
      const T tz = g.t[2];
      T J[6];
      projection_jacobian(fx, fy, sk, tz, g.ac, g.bc, J);
      T g_tz = 0;
      for (int k = 0; k < 6; ++k) g_tz -= gJ[k] * J[k] / tz;  // every entry of J is ∝ 1/z
      T g_ac = -fx * gJ[2] / tz;
      T g_bc = -(sk * gJ[2] + fy * gJ[5]) / tz;
      // Through the frustum clamp: a clamped coordinate is constant in its own argument.
      if (g.u_clamped) g_bc -= sk / fx * g_ac, g_ac = 0;
      T g_a = g_ac, g_b = g.v_clamped ? T(0) : g_bc;
      // Mean: u = fx·a + skew·b + cx, v = fy·b + cy.
      g_a += fx * gu;
      g_b += sk * gu + fy * gv;
      const T g_t[3] = {g_a / tz, g_b / tz, g_tz + gdepth - (g_a * g.a + g_b * g.b) / tz};
      for (int c = 0; c < 3; ++c) gm[c] = T(R[c]) * g_t[0] + T(R[3 + c]) * g_t[1] + T(R[6 + c]) * g_t[2];
    }
  });
}

}  // namespace

Projection project_fwd(const torch::Tensor& means, const torch::Tensor& scales, const torch::Tensor& quats,
                       const torch::Tensor& colors, const torch::Tensor& opacities, const CameraParams& cam,
                       const ProjectSettings& settings) {
  const int64_t n = means.size(0);
  Projection out;
  out.packed = torch::empty({n, kRec}, means.options());
  out.rects = torch::empty({n, 4}, means.options().dtype(torch::kInt32));
  AT_DISPATCH_FLOATING_TYPES(means.scalar_type(), "project_fwd", [&] {
    project_fwd_impl<scalar_t>(means.data_ptr<scalar_t>(), scales.data_ptr<scalar_t>(), quats.data_ptr<scalar_t>(),
                               colors.data_ptr<scalar_t>(), opacities.data_ptr<scalar_t>(), n, cam, settings,
                               out.packed.data_ptr<scalar_t>(), out.rects.data_ptr<int32_t>(), out.nonfinite);
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
    project_bwd_impl<scalar_t>(means.data_ptr<scalar_t>(), scales.data_ptr<scalar_t>(), quats.data_ptr<scalar_t>(),
                               opacities.data_ptr<scalar_t>(), n, cam, settings, grad2d.data_ptr<scalar_t>(),
                               out.means.data_ptr<scalar_t>(), out.scales.data_ptr<scalar_t>(),
                               out.quats.data_ptr<scalar_t>(), out.opacities.data_ptr<scalar_t>());
  });
  return out;
}

}  // namespace isplat::splat
