// nerfstudio transforms.json reading and writing.
#include "data/nerfstudio.h"

#include <Eigen/Dense>
#include <cmath>
#include <filesystem>
#include <functional>
#include <map>

#include "core/config.h"
#include "core/error.h"
#include "core/log.h"
#include "core/runtime.h"
#include "geometry/convert.h"
#include "io/atomic_file.h"
#include "io/image_io.h"

namespace isplat {
namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

double number(const json& j, const char* key, const std::string& where) {
  if (!j.contains(key)) fail(where, ": missing key '", key, "'");
  if (!j[key].is_number()) fail(where, ": key '", key, "' must be a number, got ", j[key].dump());
  return j[key].get<double>();
}

Eigen::Matrix4d matrix(const json& j, int rows, const std::string& where, const char* key) {
  if (!j.is_array() || static_cast<int>(j.size()) != rows) fail(where, ": '", key, "' must have ", rows, " rows of 4");
  Eigen::Matrix4d M = Eigen::Matrix4d::Identity();
  for (int r = 0; r < rows; ++r) {
    if (!j[r].is_array() || j[r].size() != 4) fail(where, ": '", key, "' row ", r, " must have 4 numbers");
    for (int c = 0; c < 4; ++c) {
      if (!j[r][c].is_number()) fail(where, ": '", key, "' has a non-number at [", r, "][", c, "]");
      M(r, c) = j[r][c].get<double>();
    }
  }
  if (!M.allFinite()) fail(where, ": '", key, "' is not finite");
  // A singular rotation part maps every camera onto a plane or a point: "0 pairs" and no error otherwise.
  if (!(std::fabs(M.topLeftCorner<3, 3>().determinant()) > 1e-12)) fail(where, ": '", key, "' is singular");
  return M;
}

// A camera-to-world rotation must be rigid: orthonormal columns and no mirror. A scaled or sheared one would be read
// as a different camera than the one that took the photo, silently. 1e-3 admits float32 writers' rounding.
void check_rigid(const Eigen::Matrix4d& c2w, const std::string& where) {
  const Eigen::Matrix3d R = c2w.topLeftCorner<3, 3>();
  const double off = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  const double bottom = (c2w.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff();
  if (bottom > 1e-6) fail(where, ": the last row of 'transform_matrix' is not 0 0 0 1; not a rigid camera pose");
  if (off > 1e-3 || R.determinant() < 0)
    fail(where, ": the rotation part of 'transform_matrix' (after undoing 'applied_transform') is not a rotation (",
         R.determinant() < 0 ? "it mirrors" : cat("columns off orthonormal by ", off),
         "); the file contradicts itself, re-export the poses");
}

// Intrinsics from an object holding fl_x/fl_y/cx/cy/w/h (frame keys override the global ones), or, in the
// NeRF-synthetic style, camera_angle_x (and camera_angle_y) with the size read from `image_size`.
Intrinsics intrinsics(const json& global, const json& frame, const std::string& where, std::vector<double>& dist,
                      const std::function<cv::Size()>& image_size) {
  auto pick = [&](const char* key) -> const json& { return frame.contains(key) ? frame : global; };
  Intrinsics k;
  if (pick("w").contains("w") && pick("h").contains("h")) {
    const double w = number(pick("w"), "w", where), h = number(pick("h"), "h", where);
    if (!(w >= 1 && h >= 1 && w * h <= static_cast<double>(max_image_pixels())))
      fail(where, ": image size ", w, "x", h, " is not positive or above runtime.max_image_pixels");
    k.width = static_cast<int>(w), k.height = static_cast<int>(h);
  } else {
    const cv::Size size = image_size();
    k.width = size.width, k.height = size.height;
  }
  if (pick("fl_x").contains("fl_x")) {
    k.fx = number(pick("fl_x"), "fl_x", where);
  } else if (pick("camera_angle_x").contains("camera_angle_x")) {
    const double ax = number(pick("camera_angle_x"), "camera_angle_x", where);
    if (!(ax > 0 && ax < M_PI)) fail(where, ": camera_angle_x = ", ax, " is not an angle in (0, pi) radians");
    k.fx = 0.5 * k.width / std::tan(0.5 * ax);
  } else {
    fail(where, ": missing key 'fl_x' (or 'camera_angle_x')");
  }
  if (pick("fl_y").contains("fl_y")) {
    k.fy = number(pick("fl_y"), "fl_y", where);
  } else if (!pick("fl_x").contains("fl_x") && pick("camera_angle_y").contains("camera_angle_y")) {
    const double ay = number(pick("camera_angle_y"), "camera_angle_y", where);
    if (!(ay > 0 && ay < M_PI)) fail(where, ": camera_angle_y = ", ay, " is not an angle in (0, pi) radians");
    k.fy = 0.5 * k.height / std::tan(0.5 * ay);
  } else {
    k.fy = k.fx;
  }
  if (!(std::isfinite(k.fx) && k.fx > 0 && std::isfinite(k.fy) && k.fy > 0))
    fail(where, ": focal length fx ", k.fx, ", fy ", k.fy, " must be finite and positive");
  k.cx = pick("cx").contains("cx") ? number(pick("cx"), "cx", where) : k.width / 2.0;
  k.cy = pick("cy").contains("cy") ? number(pick("cy"), "cy", where) : k.height / 2.0;
  std::string model = "OPENCV";
  if (pick("camera_model").contains("camera_model")) {
    const json& m = pick("camera_model")["camera_model"];
    if (!m.is_string()) fail(where, ": key 'camera_model' must be a string, got ", m.dump());
    model = m.get<std::string>();
  }
  auto coef = [&](const char* key) { return pick(key).contains(key) ? number(pick(key), key, where) : 0.0; };
  dist.clear();
  if (model == "OPENCV") {
    dist = {coef("k1"), coef("k2"), coef("p1"), coef("p2"), coef("k3"), coef("k4"), 0.0, 0.0};
  } else if (model == "OPENCV_FISHEYE") {
    if (coef("k1") != 0 || coef("k2") != 0 || coef("k3") != 0 || coef("k4") != 0)
      fail(where, ": camera_model OPENCV_FISHEYE with non-zero distortion is not supported; undistort first");
  } else if (model != "PINHOLE" && model != "SIMPLE_PINHOLE") {
    fail(where, ": unsupported camera_model '", model, "' (PINHOLE, OPENCV, OPENCV_FISHEYE without distortion)");
  }
  if (std::all_of(dist.begin(), dist.end(), [](double x) { return x == 0.0; })) dist.clear();
  return k;
}

// The frames of a parsed transforms.json; `path` names the file in errors.
Sequence read_sequence(const json& j, const std::string& scene_dir, const std::string& dataset,
                       const std::string& path) {
  if (!j.is_object() || !j.contains("frames") || !j["frames"].is_array()) fail(path, ": missing 'frames' list");
  if (j["frames"].empty()) fail(path, ": 'frames' is empty (empty sequence)");
  Eigen::Matrix4d undo = Eigen::Matrix4d::Identity();
  if (j.contains("applied_transform")) undo = matrix(j["applied_transform"], 3, path, "applied_transform").inverse();

  Sequence seq;
  seq.dataset = dataset;
  seq.scene = fs::path(scene_dir).filename().string();
  seq.name = "nerfstudio";
  std::vector<json> frames(j["frames"].begin(), j["frames"].end());
  for (size_t i = 0; i < frames.size(); ++i)
    if (!frames[i].is_object() || !frames[i].contains("file_path") || !frames[i]["file_path"].is_string())
      fail(path, ": frame ", i, " has no 'file_path'");
  {  // Two frames of one image (however spelled: "./a.png", "a.png") give it two poses: which is right?
    std::map<std::string, size_t> first;
    for (size_t i = 0; i < frames.size(); ++i) {
      const std::string key = fs::path(frames[i]["file_path"].get<std::string>()).lexically_normal().string();
      const auto [it, fresh] = first.emplace(key, i);
      if (!fresh)
        fail(path, ": frames ", it->second, " and ", i, " both name the image '", key, "' (a duplicated frame)");
    }
  }
  std::sort(frames.begin(), frames.end(), [](const json& a, const json& b) {
    return a["file_path"].get<std::string>() < b["file_path"].get<std::string>();
  });
  cv::Size first_size;  // NeRF-synthetic files give no w/h: the first image's size, read once
  bool any_depth = false;
  for (const auto& fr : frames) {
    const std::string rel = fr["file_path"].get<std::string>();
    const std::string where = path + " frame '" + rel + "'";
    FrameRecord f;
    f.name = seq.scene + "/" + rel;
    f.image_path = (fs::path(scene_dir) / rel).string();
    // NeRF-synthetic (and instant-ngp's examples) name frames without the extension: "./train/r_0".
    if (!fs::exists(f.image_path) && fs::path(rel).extension().empty())
      for (const char* ext : {".png", ".jpg", ".jpeg", ".PNG", ".JPG"})
        if (fs::exists(f.image_path + ext)) {
          f.image_path += ext;
          break;
        }
    if (!fs::exists(f.image_path)) fail(where, ": image file ", f.image_path, " does not exist");
    const std::string image_path = f.image_path;
    auto image_size = [&]() {
      if (first_size.area() == 0) {
        first_size = read_image(image_path).size();  // no 'w'/'h' given: the checked reader finds the size
      }
      return first_size;
    };
    if (!fr.contains("transform_matrix")) fail(where, ": missing 'transform_matrix'");
    const Eigen::Matrix4d c2w = undo * matrix(fr["transform_matrix"], 4, where, "transform_matrix");
    check_rigid(c2w, where);
    f.view.T_cw = pose_from_opengl_c2w(c2w);
    f.view.intr = intrinsics(j, fr, where, f.distortion, image_size);
    f.rescale_to_image = true;
    if (fr.contains("depth_file_path")) {
      if (!fr["depth_file_path"].is_string()) fail(where, ": key 'depth_file_path' must be a string");
      const std::string d = (fs::path(scene_dir) / fr["depth_file_path"].get<std::string>()).string();
      const std::string ext = fs::path(d).extension().string();
      if (fs::exists(d)) {
        f.depth_path = d;
        f.depth = ext == ".exr" ? DepthSource::PlanarExr : DepthSource::Png16Millimetres;
        any_depth = true;
      }
    }
    seq.frames.push_back(std::move(f));
  }
  if (!any_depth)
    log_warn(path,
             ": no depth files, so nothing fixes the poses' scale; baselines and the protocol's bins assume "
             "metres. Unless the poses are metric (a metric SLAM or LiDAR capture), scale them first.");
  return seq;
}
}  // namespace

Sequence nerfstudio_sequence(const std::string& scene_dir, const std::string& dataset,
                             const std::string& transforms_name) {
  const std::string path = (fs::path(scene_dir) / transforms_name).string();
  const json j = read_json_file(path);
  return guard_json(path, [&] { return read_sequence(j, scene_dir, dataset, path); });
}

void write_nerfstudio(const std::string& scene_dir, const Intrinsics& intr,
                      const std::vector<NerfstudioFrameOut>& frames, const Eigen::Matrix4d& applied_transform) {
  json j;
  j["camera_model"] = "OPENCV";
  j["fl_x"] = intr.fx;
  j["fl_y"] = intr.fy;
  j["cx"] = intr.cx;
  j["cy"] = intr.cy;
  j["w"] = intr.width;
  j["h"] = intr.height;
  for (const char* k : {"k1", "k2", "p1", "p2"}) j[k] = 0.0;
  json at = json::array();
  for (int r = 0; r < 3; ++r)
    at.push_back({applied_transform(r, 0), applied_transform(r, 1), applied_transform(r, 2), applied_transform(r, 3)});
  j["applied_transform"] = at;
  j["frames"] = json::array();
  for (const auto& f : frames) {
    const Eigen::Matrix4d c2w = applied_transform * opengl_c2w_from_pose(f.T_cw);
    json m = json::array();
    for (int r = 0; r < 4; ++r) m.push_back({c2w(r, 0), c2w(r, 1), c2w(r, 2), c2w(r, 3)});
    json fr = {{"file_path", f.file_path}, {"transform_matrix", m}};
    if (!f.depth_file_path.empty()) fr["depth_file_path"] = f.depth_file_path;
    j["frames"].push_back(fr);
  }
  write_file_atomic((fs::path(scene_dir) / "transforms.json").string(), j.dump(2));
}

}  // namespace isplat
