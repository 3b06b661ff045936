// scene.camera.json reading and writing.
#include "cli/scene_camera.h"

#include <filesystem>
#include <nlohmann/json.hpp>

#include "core/error.h"
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
  try {
    const auto j = nlohmann::json::parse(read_file_bytes(path));
    Eigen::Matrix3d K;
    View v;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) K(r, c) = j.at("K").at(r).at(c).get<double>();
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) v.T_cw(r, c) = j.at("T_cw").at(r).at(c).get<double>();
    v.intr = Intrinsics::from_K(K, j.at("width").get<int>(), j.at("height").get<int>());
    typical_depth = j.value("typical_depth", 3.0);
    return v;
  } catch (const nlohmann::json::exception& e) {
    fail(path, ": malformed scene camera: ", e.what());
  }
}

}  // namespace isplat::cli
