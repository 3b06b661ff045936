// Orbit, dolly and file camera paths.
#include "geometry/trajectory.h"

#include <Eigen/Dense>
#include <cmath>
#include <nlohmann/json.hpp>

#include "core/config.h"
#include "core/error.h"
#include "core/runtime.h"
#include "geometry/convert.h"

namespace isplat {

namespace {
// World-to-camera for a camera at `c` looking at `target`, with the source's up direction.
Pose look_at(const Eigen::Vector3d& c, const Eigen::Vector3d& target, const Eigen::Vector3d& up_hint) {
  const Eigen::Vector3d f = (target - c).normalized();
  Eigen::Vector3d r = f.cross(up_hint);  // OpenCV: right = forward x up
  if (r.norm() < 1e-9) r = Eigen::Vector3d::UnitX();
  r.normalize();
  const Eigen::Vector3d d = f.cross(r);
  Eigen::Matrix3d R_wc;
  R_wc << r, d, f;
  return invert_pose(make_pose(R_wc, c));
}
}  // namespace

CameraPath orbit_path(const View& base, double depth, int frames, double radius_fraction) {
  ISPLAT_CHECK(frames > 0 && depth > 0, "orbit: frames and depth must be positive");
  const Pose T_wc = invert_pose(base.T_cw);
  const Eigen::Matrix3d R = T_wc.topLeftCorner<3, 3>();
  const Eigen::Vector3d c0 = T_wc.topRightCorner<3, 1>(), target = c0 + R.col(2) * depth, up = -R.col(1);
  CameraPath p;
  const double r = radius_fraction * depth;
  for (int i = 0; i < frames; ++i) {
    const double a = 2 * M_PI * i / frames;
    const Eigen::Vector3d c = c0 + R.col(0) * (r * std::sin(a)) + R.col(1) * (0.5 * r * (1 - std::cos(a)));
    p.views.push_back({base.intr, look_at(c, target, up)});
  }
  return p;
}

CameraPath dolly_path(const View& base, double depth, int frames, double travel_fraction) {
  ISPLAT_CHECK(frames > 0 && depth > 0, "dolly: frames and depth must be positive");
  const Pose T_wc = invert_pose(base.T_cw);
  const Eigen::Vector3d axis = T_wc.block<3, 1>(0, 2);
  CameraPath p;
  for (int i = 0; i < frames; ++i) {
    const double s = travel_fraction * depth * std::sin(2 * M_PI * i / frames);  // forward, back, back, forward
    Pose T = base.T_cw;
    T.topRightCorner<3, 1>() -= T.topLeftCorner<3, 3>() * (axis * s);
    p.views.push_back({base.intr, T});
  }
  return p;
}

namespace {
// Rows of numbers, each checked: short rows and non-numbers are errors naming the file and the key.
Eigen::MatrixXd matrix_at(const nlohmann::json& v, int rows, int cols, const std::string& path,
                          const std::string& where) {
  if (!v.is_array() || static_cast<int>(v.size()) != rows) fail(path, ": ", where, " must have ", rows, " rows");
  Eigen::MatrixXd M(rows, cols);
  for (int r = 0; r < rows; ++r) {
    if (!v[r].is_array() || static_cast<int>(v[r].size()) != cols)
      fail(path, ": ", where, " row ", r, " must hold ", cols, " numbers");
    for (int c = 0; c < cols; ++c) {
      if (!v[r][c].is_number()) fail(path, ": ", where, "[", r, "][", c, "] must be a number");
      M(r, c) = v[r][c].get<double>();
    }
  }
  if (!M.allFinite()) fail(path, ": ", where, " is not finite");
  return M;
}

CameraPath read_camera_path(const nlohmann::json& j, const std::string& path, const View& base) {
  auto number = [&](const nlohmann::json& v, const std::string& where) {
    if (!v.is_number() || !std::isfinite(v.get<double>())) fail(path, ": ", where, " must be a number");
    return v.get<double>();
  };
  // The output size is allocated per frame: refuse what no renderer here could hold before it is tried.
  auto resized = [&](const Intrinsics& intr, const char* wkey, const char* hkey) {
    const double w = number(j[wkey], wkey), h = number(j[hkey], hkey);
    if (!(w >= 1 && h >= 1 && w * h <= static_cast<double>(max_image_pixels())))
      fail(path, ": ", wkey, " x ", hkey, " = ", w, "x", h, " is not a usable image size (runtime.max_image_pixels)");
    return intr.resized(static_cast<int>(w), static_cast<int>(h));
  };
  if (!j.is_object()) fail(path, ": expected a JSON object");
  CameraPath p;
  Intrinsics intr = base.intr;
  if (j.contains("width") && j.contains("height")) intr = resized(intr, "width", "height");
  if (j.contains("frames")) {
    if (!j["frames"].is_array()) fail(path, ": 'frames' must be a list");
    for (size_t i = 0; i < j["frames"].size(); ++i) {
      const auto& f = j["frames"][i];
      const std::string where = cat("frames[", i, "]");
      if (!f.is_object() || !f.contains("T_cw")) fail(path, ": ", where, ".T_cw must be a 4x4 matrix");
      View v{intr, Pose::Identity()};
      v.T_cw = matrix_at(f["T_cw"], 4, 4, path, where + ".T_cw");
      if (f.contains("K")) {
        const Eigen::Matrix3d K = matrix_at(f["K"], 3, 3, path, where + ".K");
        if (!(K(0, 0) > 0 && K(1, 1) > 0)) fail(path, ": ", where, ".K has a focal length that is not positive");
        v.intr = Intrinsics::from_K(K, intr.width, intr.height);
      }
      p.views.push_back(v);
    }
  } else if (j.contains("camera_path")) {
    if (!j["camera_path"].is_array()) fail(path, ": 'camera_path' must be a list");
    if (j.contains("render_width") && j.contains("render_height"))
      intr = resized(intr, "render_width", "render_height");
    for (size_t i = 0; i < j["camera_path"].size(); ++i) {
      const auto& f = j["camera_path"][i];
      const std::string where = cat("camera_path[", i, "]");
      if (!f.is_object() || !f.contains("camera_to_world") || !f["camera_to_world"].is_array() ||
          f["camera_to_world"].size() != 16)
        fail(path, ": ", where, ".camera_to_world must hold 16 numbers (row-major 4x4)");
      Eigen::Matrix4d c2w;
      for (int k = 0; k < 16; ++k) c2w(k / 4, k % 4) = number(f["camera_to_world"][k], where + ".camera_to_world");
      View v{intr, pose_from_opengl_c2w(c2w)};
      if (f.contains("fov")) {  // nerfstudio stores the vertical field of view in degrees
        const double fov = number(f["fov"], where + ".fov");
        if (!(fov > 0 && fov < 180)) fail(path, ": ", where, ".fov must be in (0, 180) degrees");
        const double fy = 0.5 * intr.height / std::tan(0.5 * fov * M_PI / 180.0);
        v.intr.fx = v.intr.fy = fy;
      }
      p.views.push_back(v);
    }
  } else {
    fail(path, ": expected a 'frames' list (T_cw per frame) or a nerfstudio 'camera_path'");
  }
  if (p.views.empty()) fail(path, ": the camera path has no frames");
  return p;
}
}  // namespace

CameraPath load_camera_path(const std::string& path, const View& base) {
  const nlohmann::json j = read_json_file(path);
  return guard_json(path, [&] { return read_camera_path(j, path, base); });
}

}  // namespace isplat
