// PlayCanvas's splat-transform CLI (npm @playcanvas/splat-transform, run by node): writes the self-contained
// HTML viewer page, and converts our files with a reader that is not ours (the tests use it to check them).
#pragma once
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "core/gaussians.h"

namespace isplat {

// The installed CLI script (<package>/bin/cli.mjs).
struct SplatTransformTool {
  std::string cli;
};

// ISPLAT_SPLAT_TRANSFORM when set (the package folder or its cli.mjs), otherwise
// third_party/splat-transform/node_modules/@playcanvas/splat-transform found by resolve_shipped_path (the
// working directory, then the folders above the executable). scripts/setup.sh installs it there.
SplatTransformTool find_splat_transform();
// The tool of a checkout at `root` (tests know their source tree).
SplatTransformTool splat_transform_in(const std::string& root);

// Runs `node <cli> args...` and returns what it printed. Returns nullopt with `why` set when node or the
// package is missing; a failing run throws Error with its output.
std::optional<std::string> run_splat_transform(const SplatTransformTool& tool, const std::vector<std::string>& args,
                                               std::string& why);

// Where the viewer's camera starts and what it looks at, in our frame (OpenCV: x right, y down, z forward;
// metres), and its field of view, which the viewer applies along the longer side of its window.
struct ViewerCamera {
  std::array<double, 3> position{0, 0, 0};
  std::array<double, 3> target{0, 0, 1};
  double fov_deg = 60;
};
// The source camera of a predicted scene: at the origin, looking down +z at the median depth of the
// Gaussians in front of it (1 m when none is).
ViewerCamera source_viewer_camera(const Gaussians& g, double fov_deg = 60);

// Writes `path` (must end in .html): one page holding PlayCanvas's SuperSplat viewer and the scene (as SOG),
// opening at `camera`. The viewer turns the scene 180 degrees about z (its world is (-x, -y, z) of ours,
// y up), so the camera is given to it turned the same way. Returns false with `why` when node or
// splat-transform is missing; failures throw Error. Written atomically.
bool write_html_viewer(const std::string& path, const Gaussians& g, const ViewerCamera& camera,
                       const SplatTransformTool& tool, std::string& why, bool colors_linear = true);

}  // namespace isplat
