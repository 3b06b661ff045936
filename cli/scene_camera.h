// The camera a predicted scene was made from, stored beside its PLY (scene.camera.json), so `render`
// starts where `predict` looked.
#pragma once
#include <string>

#include "geometry/camera.h"

namespace isplat::cli {

std::string camera_sidecar_path(const std::string& ply_path);  // scene.ply -> scene.camera.json
void write_scene_camera(const std::string& path, const View& view, double typical_depth);
View read_scene_camera(const std::string& path, double& typical_depth);

}  // namespace isplat::cli
