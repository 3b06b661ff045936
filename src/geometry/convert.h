// Converters from dataset camera conventions (COLMAP, nerfstudio/OpenGL, Hypersim) to T_cw + K.
#pragma once
#include <Eigen/Core>

#include "geometry/camera.h"

namespace isplat {

// COLMAP stores world->camera as a unit quaternion (qw, qx, qy, qz) and translation: already T_cw.
Eigen::Matrix3d rotation_from_quaternion(const Eigen::Vector4d& q_wxyz);
Eigen::Vector4d quaternion_from_rotation(const Eigen::Matrix3d& R);  // (w, x, y, z), w >= 0
Pose pose_from_colmap(const Eigen::Vector4d& qvec_wxyz, const Eigen::Vector3d& tvec);
void pose_to_colmap(const Pose& T_cw, Eigen::Vector4d& qvec_wxyz, Eigen::Vector3d& tvec);

// nerfstudio / OpenGL camera-to-world (x right, y up, z back): negate columns 1 and 2, then invert.
Pose pose_from_opengl_c2w(const Eigen::Matrix4d& c2w);
Eigen::Matrix4d opengl_c2w_from_pose(const Pose& T_cw);

// Hypersim camera model. M_cam_from_uv maps (u, v, 1), u = 2(j+0.5)/W - 1 (right), v = 1 - 2(i+0.5)/H (up),
// to a ray direction in the OpenGL camera frame. Tilt-shift cameras have a general M; we recover the
// exact pinhole by RQ-decomposing S·M⁻¹·F = K·R (DESIGN §4), and fold R into the pose.
struct HypersimCamera {
  Intrinsics intr;
  Eigen::Matrix3d R_eff = Eigen::Matrix3d::Identity();  // OpenCV camera frame -> effective pinhole frame
  bool tilt_shift = false;                              // M has a non-trivial third row or shift

  // Ray direction (unnormalized) in the OpenGL camera frame for continuous pixel (x, y): M·[u, v, 1].
  Eigen::Vector3d ray_gl(double x, double y) const;
  Eigen::Matrix3d M_cam_from_uv;
};

HypersimCamera hypersim_camera(const Eigen::Matrix3d& M_cam_from_uv, int width, int height);

// Pose of the effective pinhole camera from a Hypersim keyframe: orientation R_world_from_cam (OpenGL
// camera axes, columns = camera axes in world), position in asset units, scaled to metres.
Pose pose_from_hypersim(const Eigen::Matrix3d& R_world_from_cam_gl, const Eigen::Vector3d& position_asset,
                        double meters_per_asset_unit, const HypersimCamera& camera);

// Factor turning Hypersim's distance-along-ray into planar depth along the effective camera's z axis,
// for continuous pixel (x, y): z = distance * factor.
double hypersim_planar_factor(const HypersimCamera& camera, double x, double y);

// RQ decomposition A = R·Q with R upper-triangular (positive diagonal) and Q orthonormal (det +1 when
// A has positive determinant); A is treated as homogeneous, so its sign may be flipped. Exposed for tests.
void rq_decompose(const Eigen::Matrix3d& A, Eigen::Matrix3d& R_upper, Eigen::Matrix3d& Q);

}  // namespace isplat
