// Dense per-pixel reference renderer for the render tests (torch ops; O(pixels × N) memory, small scenes only).
#include "support/reference_render.h"

#include <torch/torch.h>

#include <cmath>

namespace isplat::test {
using torch::Tensor;
namespace {

struct Projected {
  Tensor u, v, A, B, C, opac, z, normal;  // [N] each, normal [N, 3]
  Tensor valid;                           // [N] bool
};

Projected project(const Gaussians& g, const Camera& cam, const RenderOptions& opt) {
  const auto dt = g.means.scalar_type();
  const Tensor K = cam.K.to(dt), Tcw = cam.T_cw.to(dt);
  const double fx = K[0][0].item<double>(), sk = K[0][1].item<double>(), cx = K[0][2].item<double>();
  const double fy = K[1][1].item<double>(), cy = K[1][2].item<double>();
  const Tensor R = Tcw.slice(0, 0, 3).slice(1, 0, 3), tv = Tcw.slice(0, 0, 3).select(1, 3);
  const Tensor t = torch::matmul(g.means, R.t()) + tv;
  const Tensor z = t.select(1, 2);
  const Tensor q = g.quats / g.quats.norm(2, 1, true);
  const Tensor w = q.select(1, 0), x = q.select(1, 1), y = q.select(1, 2), qz = q.select(1, 3);
  const Tensor Rq = torch::stack({1 - 2 * (y * y + qz * qz), 2 * (x * y - w * qz), 2 * (x * qz + w * y),
                                  2 * (x * y + w * qz), 1 - 2 * (x * x + qz * qz), 2 * (y * qz - w * x),
                                  2 * (x * qz - w * y), 2 * (y * qz + w * x), 1 - 2 * (x * x + y * y)},
                                 1)
                        .reshape({-1, 3, 3});
  const Tensor M = Rq * g.scales.unsqueeze(1);
  const Tensor cov3 = torch::matmul(torch::matmul(R, torch::matmul(M, M.transpose(1, 2))), R.t());
  const Tensor a = t.select(1, 0) / z, b = t.select(1, 1) / z;
  const double W = double(cam.width), H = double(cam.height);
  const double blo = (-0.15 * H - cy) / fy, bhi = (1.15 * H - cy) / fy;
  const Tensor bc = torch::clamp(b, blo, bhi);
  const Tensor uc = torch::clamp(fx * a + sk * bc + cx, -0.15 * W, 1.15 * W);
  const Tensor ac = (uc - cx - sk * bc) / fx;
  const Tensor zero = torch::zeros_like(z);
  const Tensor J =
      torch::stack({fx / z, sk / z, -(fx * ac + sk * bc) / z, zero, fy / z, -fy * bc / z}, 1).reshape({-1, 2, 3});
  const Tensor cov2 = torch::matmul(torch::matmul(J, cov3), J.transpose(1, 2));
  const Tensor sa = cov2.select(1, 0).select(1, 0), sb = cov2.select(1, 0).select(1, 1),
               sc = cov2.select(1, 1).select(1, 1);
  const double d = opt.dilation;
  const Tensor det = (sa + d) * (sc + d) - sb * sb;
  Projected p;
  p.u = fx * a + sk * b + cx;
  p.v = fy * b + cy;
  p.A = (sc + d) / det, p.B = -sb / det, p.C = (sa + d) / det;
  p.opac = opt.antialiased ? g.opacities * torch::sqrt((sa * sc - sb * sb) / det) : g.opacities;
  p.z = z;
  // Normal: first smallest scale axis, in camera space, facing the camera.
  const Tensor k = std::get<1>(torch::min(g.scales, 1));
  const Tensor axis = torch::gather(Rq, 2, k.view({-1, 1, 1}).expand({-1, 3, 1})).squeeze(2);
  Tensor n = torch::matmul(axis, R.t());
  n = torch::where(((n * t).sum(1, true) > 0), -n, n);
  p.normal = n.detach();
  p.valid = (z >= opt.near) & (g.scales > 0).all(1) & (g.opacities > 0) & (det > 0) & (255 * p.opac > 1);
  return p;
}

}  // namespace

RenderOutput reference_render(const Gaussians& gaussians, const Camera& camera, const RenderOptions& options,
                              const RenderMaps& maps) {
  // Decide validity without gradients, then recompute on the valid subset only (so no NaN can leak into
  // the gradients through masked-out branches).
  Tensor keep;
  {
    torch::NoGradGuard no_grad;
    keep = project(gaussians.detach(), camera, options).valid.nonzero().squeeze(1);
  }
  const Gaussians g = gaussians.index(keep);
  const Projected p = project(g, camera, options);
  const auto dt = g.means.scalar_type();
  const int64_t H = camera.height, W = camera.width, n = g.means.size(0);
  const Tensor order = std::get<1>(torch::sort(p.z.detach(), /*stable=*/true, /*dim=*/0, /*descending=*/false));
  auto sorted = [&](const Tensor& t) { return t.index_select(0, order); };
  const Tensor u = sorted(p.u), v = sorted(p.v), A = sorted(p.A), B = sorted(p.B), C = sorted(p.C);
  const Tensor opac = sorted(p.opac), z = sorted(p.z), colors = sorted(g.colors), normal = sorted(p.normal);
  const Tensor cut = torch::clamp_max(torch::log(255 * opac.detach()), 4.5);

  const auto opts = torch::TensorOptions().dtype(dt);
  const Tensor py = (torch::arange(H, opts) + 0.5).view({H, 1}).expand({H, W}).reshape({-1, 1});
  const Tensor px = (torch::arange(W, opts) + 0.5).view({1, W}).expand({H, W}).reshape({-1, 1});
  const Tensor dx = px - u.view({1, n}), dy = py - v.view({1, n});  // [P, N]
  const Tensor power = 0.5 * (A * dx * dx + C * dy * dy) + B * dx * dy;
  const Tensor raw = opac * torch::exp(-power);
  const Tensor hit = (power <= cut) & (raw >= 1.0 / 255.0);
  const Tensor alpha = torch::where(hit, torch::clamp_max(raw, 0.99), torch::zeros_like(raw));
  const Tensor T_after = torch::cumprod(1 - alpha, 1);
  Tensor contrib;
  {
    torch::NoGradGuard no_grad;  // the first Gaussian that would take T below 1e-4 and all behind it are out
    contrib = (torch::cumsum((T_after < 1e-4).to(torch::kInt64), 1) == 0).to(dt);
  }
  const Tensor T_before =
      torch::cat({torch::ones({H * W, 1}, opts), T_after.slice(1, 0, n - 1 < 0 ? 0 : n - 1)}, 1).slice(1, 0, n);
  const Tensor wts = alpha * T_before * contrib;
  const Tensor T_final = torch::prod(1 - alpha * contrib, 1);
  const Tensor bg = torch::tensor(options.background, opts);
  RenderOutput out;
  out.rgb = (torch::matmul(wts, colors) + T_final.unsqueeze(1) * bg).t().reshape({3, H, W});
  out.alpha = (1 - T_final).reshape({1, H, W});
  out.depth = torch::matmul(wts, z).reshape({1, H, W});
  out.normal = torch::matmul(wts.detach(), normal).t().reshape({3, H, W});
  if (maps.median_depth) {  // the first composited Gaussian that leaves T at 0.5 or below
    torch::NoGradGuard no_grad;
    const Tensor crossed = ((torch::cumprod(1 - alpha * contrib, 1) <= 0.5) & (wts > 0)).to(torch::kInt64);
    const Tensor first = crossed * (torch::cumsum(crossed, 1) == 1);
    out.median_depth = torch::matmul(first.to(dt), z.detach()).reshape({1, H, W});
  }
  return out;
}

}  // namespace isplat::test
