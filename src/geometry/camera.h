// Pinhole intrinsics and world->camera poses (OpenCV axes), in Eigen for data code.
#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace isplat {

// Pixel (col j, row i) has its centre at continuous coordinate (j + 0.5, i + 0.5); K maps camera
// space (x right, y down, z forward) to those continuous coordinates.
// `skew` (K[0][1]) is zero for ordinary cameras; it is kept so that tilt-shift cameras stay exact.
struct Intrinsics {
  double fx = 1, fy = 1, cx = 0, cy = 0;
  int width = 0, height = 0;
  double skew = 0;

  Eigen::Matrix3d K() const;
  static Intrinsics from_K(const Eigen::Matrix3d& K, int width, int height);
  // A pinhole camera with the given horizontal field of view (radians), principal point at the centre.
  static Intrinsics from_hfov(double hfov, int width, int height);

  Eigen::Vector2d project(const Eigen::Vector3d& X_cam) const;      // requires X_cam.z() > 0
  Eigen::Vector3d backproject(double u, double v, double z) const;  // planar depth z
  Eigen::Vector3d ray(double u, double v) const;                    // direction with z = 1

  // Intrinsics after resizing the image to (new_width, new_height) (independent x/y scale).
  Intrinsics resized(int new_width, int new_height) const;
  // Intrinsics of the crop whose top-left pixel corner is (x0, y0).
  Intrinsics cropped(int x0, int y0, int crop_width, int crop_height) const;
  double hfov() const;
  bool operator==(const Intrinsics& o) const;
};

using Pose = Eigen::Matrix4d;  // T_cw: world -> camera, metres, OpenCV axes

Pose invert_pose(const Pose& T);
Eigen::Vector3d transform_point(const Pose& T, const Eigen::Vector3d& X);
Eigen::Vector3d camera_center(const Pose& T_cw);
Pose make_pose(const Eigen::Matrix3d& R, const Eigen::Vector3d& t);

// One view: intrinsics plus pose.
struct View {
  Intrinsics intr;
  Pose T_cw = Pose::Identity();

  // World point -> continuous pixel coordinate and planar depth. Returns false behind the camera.
  bool project(const Eigen::Vector3d& X_world, Eigen::Vector2d& uv, double& z) const;
  Eigen::Vector3d backproject(double u, double v, double z) const;  // to world
};

// Angle (radians) of the relative rotation between two poses.
double rotation_angle_between(const Pose& a, const Pose& b);

}  // namespace isplat
