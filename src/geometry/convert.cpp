// Dataset camera conventions -> T_cw (OpenCV axes, metres) and pinhole intrinsics.
#include "geometry/convert.h"

#include <Eigen/Dense>
#include <cmath>

#include "core/error.h"

namespace isplat {

Eigen::Matrix3d rotation_from_quaternion(const Eigen::Vector4d& q) {
  const double n = q.norm();
  ISPLAT_CHECK(n > 1e-12 && std::isfinite(n), "quaternion (", q.transpose(), ") has zero or non-finite norm");
  Eigen::Quaterniond quat(q[0] / n, q[1] / n, q[2] / n, q[3] / n);
  return quat.toRotationMatrix();
}

Eigen::Vector4d quaternion_from_rotation(const Eigen::Matrix3d& R) {
  Eigen::Quaterniond q(R);
  q.normalize();
  Eigen::Vector4d out(q.w(), q.x(), q.y(), q.z());
  return out[0] < 0 ? Eigen::Vector4d(-out) : out;
}

Pose pose_from_colmap(const Eigen::Vector4d& qvec, const Eigen::Vector3d& tvec) {
  return make_pose(rotation_from_quaternion(qvec), tvec);
}

void pose_to_colmap(const Pose& T_cw, Eigen::Vector4d& qvec, Eigen::Vector3d& tvec) {
  qvec = quaternion_from_rotation(T_cw.topLeftCorner<3, 3>());
  tvec = T_cw.topRightCorner<3, 1>();
}

static const Eigen::Matrix3d kFlipYZ = Eigen::Vector3d(1, -1, -1).asDiagonal();

Pose pose_from_opengl_c2w(const Eigen::Matrix4d& c2w) {
  Eigen::Matrix4d c2w_cv = c2w;
  c2w_cv.block<3, 1>(0, 1) *= -1.0;
  c2w_cv.block<3, 1>(0, 2) *= -1.0;
  return invert_pose(c2w_cv);
}

Eigen::Matrix4d opengl_c2w_from_pose(const Pose& T_cw) {
  Eigen::Matrix4d c2w = invert_pose(T_cw);
  c2w.block<3, 1>(0, 1) *= -1.0;
  c2w.block<3, 1>(0, 2) *= -1.0;
  return c2w;
}

void rq_decompose(const Eigen::Matrix3d& A_in, Eigen::Matrix3d& R_upper, Eigen::Matrix3d& Q) {
  // With J the exchange matrix: QR of (J·A)^T = Q~R~  =>  A = (J R~^T J)(J Q~^T).
  Eigen::Matrix3d A = A_in;
  if (A.determinant() < 0) A = -A;  // homogeneous: pick the sign that makes Q a proper rotation
  Eigen::Matrix3d J = Eigen::Matrix3d::Zero();
  J(0, 2) = J(1, 1) = J(2, 0) = 1.0;
  Eigen::HouseholderQR<Eigen::Matrix3d> qr((J * A).transpose());
  const Eigen::Matrix3d Qt = qr.householderQ();
  const Eigen::Matrix3d Rt = qr.matrixQR().triangularView<Eigen::Upper>();
  R_upper = J * Rt.transpose() * J;
  Q = J * Qt.transpose();
  // Make the diagonal of R positive; D·D = I keeps the product unchanged.
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  for (int i = 0; i < 3; ++i)
    if (R_upper(i, i) < 0) D(i, i) = -1.0;
  R_upper = R_upper * D;
  Q = D * Q;
}

Eigen::Vector3d HypersimCamera::ray_gl(double x, double y) const {
  const double u = 2.0 * x / intr.width - 1.0, v = 1.0 - 2.0 * y / intr.height;
  return M_cam_from_uv * Eigen::Vector3d(u, v, 1.0);
}

HypersimCamera hypersim_camera(const Eigen::Matrix3d& M, int width, int height) {
  ISPLAT_CHECK(width > 0 && height > 0, "Hypersim camera: image size ", width, "x", height, " is not positive");
  ISPLAT_CHECK(M.allFinite() && std::fabs(M.determinant()) > 1e-12,
               "Hypersim camera: M_cam_from_uv is singular or not finite:\n", M);
  // Continuous pixel (x, y) = S·(u, v, 1); OpenCV camera ray = F·(OpenGL ray).
  Eigen::Matrix3d S;
  S << width / 2.0, 0, width / 2.0, 0, -height / 2.0, height / 2.0, 0, 0, 1;
  const Eigen::Matrix3d P = S * M.inverse() * kFlipYZ;  // pixel ~ P · ray_cv
  Eigen::Matrix3d K, R;
  rq_decompose(P, K, R);
  K /= K(2, 2);
  HypersimCamera cam;
  cam.M_cam_from_uv = M;
  cam.intr = Intrinsics::from_K(K, width, height);
  cam.R_eff = R;
  const double off = std::fabs(M(0, 1)) + std::fabs(M(1, 0)) + std::fabs(M(2, 0)) + std::fabs(M(2, 1)) +
                     std::fabs(M(0, 2)) + std::fabs(M(1, 2));
  cam.tilt_shift = off > 1e-9;
  return cam;
}

Pose pose_from_hypersim(const Eigen::Matrix3d& R_world_from_cam_gl, const Eigen::Vector3d& position_asset,
                        double meters_per_asset_unit, const HypersimCamera& camera) {
  ISPLAT_CHECK(R_world_from_cam_gl.allFinite() && position_asset.allFinite(), "Hypersim pose is not finite");
  ISPLAT_CHECK(meters_per_asset_unit > 0, "meters_per_asset_unit must be positive, got ", meters_per_asset_unit);
  Eigen::Matrix4d c2w_gl = Eigen::Matrix4d::Identity();
  c2w_gl.topLeftCorner<3, 3>() = R_world_from_cam_gl;
  c2w_gl.topRightCorner<3, 1>() = position_asset * meters_per_asset_unit;
  const Pose T_cw_cv = pose_from_opengl_c2w(c2w_gl);
  // The effective pinhole frame is rotated by R_eff relative to the OpenCV camera frame.
  Pose R4 = Pose::Identity();
  R4.topLeftCorner<3, 3>() = camera.R_eff;
  return R4 * T_cw_cv;
}

double hypersim_planar_factor(const HypersimCamera& camera, double x, double y) {
  const Eigen::Vector3d d_gl = camera.ray_gl(x, y);
  const Eigen::Vector3d d_eff = camera.R_eff * (kFlipYZ * d_gl);
  return d_eff.z() / d_gl.norm();
}

}  // namespace isplat
