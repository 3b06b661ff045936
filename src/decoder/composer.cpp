// The release's bounded update rules: position in pixels, inverse depth through softplus, scale
// through a sigmoid with unit value and slope at zero, rotation, colour and opacity through logits.
#include "decoder/composer.h"

#include <torch/torch.h>

#include <Eigen/Core>
#include <cmath>

#include "core/config.h"
#include "core/error.h"
#include "geometry/camera_torch.h"
#include "geometry/color.h"
#include "geometry/convert.h"

namespace isplat {

void ComposerOptions::visit(ConfigVisitor& v) {
  v.field("lambda_xy", lambda_xy, "position update step in pixels (release: 1e-3 NDC at 1536 px = 0.77 px)",
          Range::at_least(0));
  v.field("lambda_z", lambda_z, "inverse-depth update step", Range::at_least(0));
  v.field("color_step", color_step, "colour logit update step", Range::at_least(0));
  v.field("scale_min", scale_min, "lower bound of the scale multiplier", Range::between(0, 1));
  v.field("scale_max", scale_max, "upper bound of the scale multiplier (> 1)", Range::above(1));
  v.field("linear_rgb", linear_rgb, "composite in linear RGB (sRGB -> linear on the colours)");
  v.field("orientation", orientation,
          "frame of the rotation update: camera (release, identity base) or surface (local z on the depth "
          "surface's normal at the support)",
          {"camera", "surface"});
  v.field("scale_floor_px", scale_floor_px,
          "every Gaussian's variance on each axis gets (scale_floor_px * z / f)^2 added, z its depth and f the "
          "source camera's focal length: none is narrower than that share of a source pixel at its depth, so "
          "views above the working size see no gaps between them (0 = off)",
          Range::between(0.0, 4.0));
}

namespace {
// Hamilton product of [...,4] wxyz quaternions.
torch::Tensor quaternion_multiply(const torch::Tensor& a, const torch::Tensor& b) {
  auto aw = a.select(-1, 0), ax = a.select(-1, 1), ay = a.select(-1, 2), az = a.select(-1, 3);
  auto bw = b.select(-1, 0), bx = b.select(-1, 1), by = b.select(-1, 2), bz = b.select(-1, 3);
  return torch::stack({aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
                       aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw},
                      -1);
}

torch::Tensor quaternion_from_matrix(const torch::Tensor& R) {
  auto r = R.to(torch::kFloat64).contiguous();
  const double* m = r.data_ptr<double>();
  Eigen::Matrix3d M;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) M(i, j) = m[i * 3 + j];
  const Eigen::Vector4d q = quaternion_from_rotation(M);  // w >= 0
  return torch::tensor({q[0], q[1], q[2], q[3]}, torch::kFloat64).to(R.scalar_type());
}
}  // namespace

torch::Tensor unclamped_opacity(const torch::Tensor& delta) {
  return torch::sigmoid(delta.select(1, 13) + std::log(0.5 / 0.5));
}

torch::Tensor inverse_softplus(const torch::Tensor& y) {
  // log(exp(y) - 1) = y + log(1 - exp(-y)); exact for small y, no overflow for large y.
  return y + torch::log(-torch::expm1(-y));
}

torch::Tensor quaternion_z_to_normal(const torch::Tensor& normal) {
  auto m = normal * (1.0 - 2.0 * (normal.select(1, 2) < 0).to(normal.scalar_type())).unsqueeze(1);
  // q = (1 + z.m, z x m) normalized, with z x m = (-m_y, m_x, 0); 1 + m_z >= 1 keeps it well conditioned.
  auto q = torch::stack({1.0 + m.select(1, 2), -m.select(1, 1), m.select(1, 0), torch::zeros_like(m.select(1, 0))}, 1);
  return q / q.norm(2, 1, true);
}

Gaussians compose_camera(const BaseGaussians& base, const torch::Tensor& delta, const torch::Tensor& K,
                         const ComposerOptions& o) {
  const int64_t N = base.count();
  ISPLAT_CHECK(delta.dim() == 2 && delta.size(0) == N && delta.size(1) == kDeltaDim, "composer: delta must be [", N,
               ", ", kDeltaDim, "], got ", delta.sizes());
  const auto dt = delta.scalar_type();
  auto uv = base.uv.to(dt), z_n = base.z_n.to(dt), s_n = base.scale_n.to(dt), color = base.color.to(dt);
  auto d_uv = delta.narrow(1, 0, 2), dz = delta.select(1, 2), ds = delta.narrow(1, 3, 3), dq = delta.narrow(1, 6, 4),
       dc = delta.narrow(1, 10, 3);

  // Position: pixel offset, then inverse depth through softplus (bounded away from zero depth).
  auto uv2 = uv + o.lambda_xy * d_uv;
  auto inv_z = torch::softplus(inverse_softplus(1.0 / z_n) + o.lambda_z * dz);
  auto z2_n = 1.0 / inv_z;
  auto means_n = backproject_points(uv2, z2_n, K.to(dt));
  // Scale: s = s_base * (z'/z) * [(smax - smin) * sigmoid(a*ds + b) + smin], equal to s_base at ds = 0.
  const double span = o.scale_max - o.scale_min;
  const double a = span / ((1.0 - o.scale_min) * (o.scale_max - 1.0));
  const double p = (1.0 - o.scale_min) / span, b = std::log(p / (1.0 - p));
  auto factor = span * torch::sigmoid(a * ds + b) + o.scale_min;
  auto scales_n = (s_n * (z2_n / z_n)).unsqueeze(1) * factor;
  // Rotation, colour and opacity.
  auto identity = torch::tensor({1.0, 0.0, 0.0, 0.0}, delta.options());
  auto quats = identity + dq;
  if (o.orientation == "surface") {
    ISPLAT_CHECK(base.normal.defined() && base.normal.sizes() == torch::IntArrayRef({N, 3}),
                 "composer.orientation = surface needs [", N, ", 3] support normals");
    quats = quaternion_multiply(quaternion_z_to_normal(base.normal.to(dt)), quats);
  }
  auto c = torch::sigmoid(torch::logit(color) + o.color_step * dc);
  c = torch::clamp(c, 0.01, 0.99);
  if (o.linear_rgb) c = srgb_to_linear(c);
  auto opacity = torch::clamp(unclamped_opacity(delta), 0.01, 0.99);
  if (o.scale_floor_px > 0) {
    // Gaussians narrower than the source's sampling interval at their depth leave gaps between them in any view
    // larger than the source: a floor on every axis closes them. Unlike Mip-Splatting's 3D filter the opacity is
    // kept, since scaling it down by the footprints' ratio reopens the same gaps (lab/2026-12-06-display-holes).
    const auto Kd = K.to(dt);
    const auto floor_n = o.scale_floor_px * z2_n / torch::sqrt(Kd[0][0] * Kd[1][1]);  // [N], normalized units
    scales_n = torch::sqrt(scales_n.pow(2) + floor_n.pow(2).unsqueeze(1));
  }
  // Back to metres.
  const double inv_df = 1.0 / base.depth_factor;
  return {means_n * inv_df, scales_n * inv_df, quats, c, opacity};
}

Gaussians camera_to_world(const Gaussians& g, const torch::Tensor& T_cw) {
  auto T_wc = invert_poses(T_cw.to(g.means.scalar_type()));
  auto q_wc = quaternion_from_matrix(T_wc.narrow(0, 0, 3).narrow(1, 0, 3)).to(g.quats.scalar_type());
  return {transform_points(T_wc, g.means), g.scales, quaternion_multiply(q_wc.expand_as(g.quats), g.quats), g.colors,
          g.opacities};
}

Gaussians compose(const BaseGaussians& base, const torch::Tensor& delta, const torch::Tensor& K,
                  const torch::Tensor& T_cw, const ComposerOptions& o) {
  return camera_to_world(compose_camera(base, delta, K, o), T_cw);
}

}  // namespace isplat
