// Pinhole intrinsics and pose helpers (Eigen).
#include "geometry/camera.h"

#include <algorithm>
#include <cmath>

namespace isplat {

Eigen::Matrix3d Intrinsics::K() const {
  Eigen::Matrix3d K;
  K << fx, skew, cx, 0, fy, cy, 0, 0, 1;
  return K;
}

Intrinsics Intrinsics::from_K(const Eigen::Matrix3d& K, int width, int height) {
  return {K(0, 0), K(1, 1), K(0, 2), K(1, 2), width, height, K(0, 1)};
}

Intrinsics Intrinsics::from_hfov(double hfov, int width, int height) {
  const double f = 0.5 * width / std::tan(0.5 * hfov);
  return {f, f, 0.5 * width, 0.5 * height, width, height};
}

Eigen::Vector2d Intrinsics::project(const Eigen::Vector3d& X) const {
  return {(fx * X.x() + skew * X.y()) / X.z() + cx, fy * X.y() / X.z() + cy};
}

Eigen::Vector3d Intrinsics::backproject(double u, double v, double z) const {
  return ray(u, v) * z;
}

Eigen::Vector3d Intrinsics::ray(double u, double v) const {
  const double y = (v - cy) / fy;
  return {(u - cx - skew * y) / fx, y, 1.0};
}

Intrinsics Intrinsics::resized(int new_width, int new_height) const {
  // Continuous coordinates scale with the image: the edges 0 and W map to 0 and W'.
  const double sx = static_cast<double>(new_width) / width, sy = static_cast<double>(new_height) / height;
  return {fx * sx, fy * sy, cx * sx, cy * sy, new_width, new_height, skew * sx};
}

Intrinsics Intrinsics::cropped(int x0, int y0, int crop_width, int crop_height) const {
  return {fx, fy, cx - x0, cy - y0, crop_width, crop_height, skew};
}

double Intrinsics::hfov() const {
  return 2.0 * std::atan(0.5 * width / fx);
}

bool Intrinsics::operator==(const Intrinsics& o) const {
  return fx == o.fx && fy == o.fy && cx == o.cx && cy == o.cy && width == o.width && height == o.height &&
         skew == o.skew;
}

Pose invert_pose(const Pose& T) {
  Pose inv = Pose::Identity();
  const Eigen::Matrix3d Rt = T.topLeftCorner<3, 3>().transpose();
  inv.topLeftCorner<3, 3>() = Rt;
  inv.topRightCorner<3, 1>() = -Rt * T.topRightCorner<3, 1>();
  return inv;
}

Eigen::Vector3d transform_point(const Pose& T, const Eigen::Vector3d& X) {
  return T.topLeftCorner<3, 3>() * X + T.topRightCorner<3, 1>();
}

Eigen::Vector3d camera_center(const Pose& T_cw) {
  return -T_cw.topLeftCorner<3, 3>().transpose() * T_cw.topRightCorner<3, 1>();
}

Pose make_pose(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  Pose T = Pose::Identity();
  T.topLeftCorner<3, 3>() = R;
  T.topRightCorner<3, 1>() = t;
  return T;
}

bool View::project(const Eigen::Vector3d& X_world, Eigen::Vector2d& uv, double& z) const {
  const Eigen::Vector3d Xc = transform_point(T_cw, X_world);
  z = Xc.z();
  if (!(z > 0)) return false;
  uv = intr.project(Xc);
  return true;
}

Eigen::Vector3d View::backproject(double u, double v, double z) const {
  return transform_point(invert_pose(T_cw), intr.backproject(u, v, z));
}

double rotation_angle_between(const Pose& a, const Pose& b) {
  const Eigen::Matrix3d R = a.topLeftCorner<3, 3>() * b.topLeftCorner<3, 3>().transpose();
  const double c = std::clamp((R.trace() - 1.0) / 2.0, -1.0, 1.0);
  return std::acos(c);
}

}  // namespace isplat
