// scene.camera.json reading and writing.
#include "cli/scene_camera.h"

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "core/config.h"
#include "core/error.h"
#include "core/runtime.h"
#include "io/atomic_file.h"

namespace isplat::cli {

std::string camera_sidecar_path(const std::string& ply_path) {
  return std::filesystem::path(ply_path).replace_extension(".camera.json").string();
}

void write_scene_camera(const std::string& path, const View& v, double typical_depth) {
  nlohmann::json j;
  j["width"] = v.intr.width;
  j["height"] = v.intr.height;
  const Eigen::Matrix3d K = v.intr.K();
  for (int r = 0; r < 3; ++r) j["K"].push_back({K(r, 0), K(r, 1), K(r, 2)});
  for (int r = 0; r < 4; ++r) j["T_cw"].push_back({v.T_cw(r, 0), v.T_cw(r, 1), v.T_cw(r, 2), v.T_cw(r, 3)});
  j["typical_depth"] = typical_depth;
  write_file_atomic(path, j.dump(2) + "\n");
}

View read_scene_camera(const std::string& path, double& typical_depth) {
  const auto j = read_json_file(path);
  return guard_json(path, [&] {
    Eigen::Matrix3d K;
    View v;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) K(r, c) = j.at("K").at(r).at(c).get<double>();
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) v.T_cw(r, c) = j.at("T_cw").at(r).at(c).get<double>();
    const int64_t width = j.at("width").get<int64_t>(), height = j.at("height").get<int64_t>();
    // The renderer allocates width x height per frame: check it and the numbers before anything is drawn.
    if (width <= 0 || height <= 0 || width > max_image_pixels() / height)
      fail(path, ": image size ", width, "x", height, " is not positive or above runtime.max_image_pixels");
    if (!K.allFinite() || !v.T_cw.allFinite() || !(K(0, 0) > 0 && K(1, 1) > 0))
      fail(path, ": K or T_cw is not finite, or a focal length is not positive");
    v.intr = Intrinsics::from_K(K, static_cast<int>(width), static_cast<int>(height));
    typical_depth = j.value("typical_depth", 3.0);
    if (!(std::isfinite(typical_depth) && typical_depth > 0)) fail(path, ": typical_depth must be positive");
    return v;
  });
}

}  // namespace isplat::cli
