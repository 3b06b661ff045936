// Camera paths for novel-view renders: a small orbit around the source view, a dolly along its axis,
// or poses from a JSON file (our T_cw list or a nerfstudio camera path).
#pragma once
#include <string>
#include <vector>

#include "geometry/camera.h"

namespace isplat {

struct CameraPath {
  std::vector<View> views;
};

// `base`: the source view (world = its camera frame for predicted scenes). `depth`: a typical scene
// depth, which sizes the motion. The orbit circles the source position while looking at the point
// `depth` ahead; the dolly moves along the optical axis from -0.3 to +0.3 depth and back.
CameraPath orbit_path(const View& base, double depth, int frames, double radius_fraction = 0.08);
CameraPath dolly_path(const View& base, double depth, int frames, double travel_fraction = 0.3);

// {"frames": [{"T_cw": [[4x4]], optional "K": [[3x3]]}], optional "width", "height"} or a nerfstudio
// camera path {"camera_path": [{"camera_to_world": [16], "fov": deg}], "render_width", "render_height"}.
// Views without intrinsics take `base.intr`. Errors name the file and the field.
CameraPath load_camera_path(const std::string& path, const View& base);

}  // namespace isplat
