// Bridge to splat-transform: one node process per call, files in and out, the viewer settings as JSON.
#include "export/splat_transform.h"

#include <unistd.h>

#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include <torch/torch.h>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "core/paths.h"
#include "io/atomic_file.h"
#include "io/ply.h"

namespace isplat {
namespace fs = std::filesystem;

namespace {

const char* kPackage = "third_party/splat-transform/node_modules/@playcanvas/splat-transform";

SplatTransformTool tool_for(const fs::path& given) {
  // A package folder or the script itself.
  return {fs::is_directory(given) ? (given / "bin" / "cli.mjs").string() : given.string()};
}

std::string shell_quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

// A fresh folder for one call's intermediate files, removed when it goes out of scope.
struct ScratchDir {
  fs::path path;
  ScratchDir() {
    static std::atomic<int> counter{0};
    path = fs::temp_directory_path() / cat("isplat_splat_transform_", getpid(), "_", counter++);
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~ScratchDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
};

// Our frame (OpenCV) to the viewer's world, ours turned 180 degrees about z.
nlohmann::json to_viewer(const std::array<double, 3>& p) {
  return nlohmann::json::array({-p[0], -p[1], p[2]});
}

// The viewer opens playing an animation; without one in the settings it makes its own, a full orbit about the
// scene's centre, which shows the empty back of a one-view scene. Ours sways the camera gently about the source
// view (a figure of eight, 8% of the viewing distance across, 10 s a loop) and starts at the source camera.
nlohmann::json sway_track(const ViewerCamera& camera, double viewing_distance) {
  const double reach = 0.04 * viewing_distance;
  nlohmann::json times = nlohmann::json::array(), positions = nlohmann::json::array(),
                 targets = nlohmann::json::array(), fovs = nlohmann::json::array();
  constexpr int kKeys = 8;
  constexpr double kSeconds = 10;
  for (int k = 0; k < kKeys; ++k) {
    const double a = 2 * M_PI * k / kKeys;
    std::array<double, 3> p = camera.position;
    p[0] += reach * std::sin(a), p[1] += 0.5 * reach * std::sin(2 * a);  // our x right, y down
    times.push_back(kSeconds * k / kKeys);
    for (const auto& v : to_viewer(p)) positions.push_back(v);
    for (const auto& v : to_viewer(camera.target)) targets.push_back(v);
    fovs.push_back(camera.fov_deg);
  }
  return {{"name", "sway"},
          {"duration", kSeconds},
          {"frameRate", 1},
          {"loopMode", "repeat"},
          {"interpolation", "spline"},
          {"smoothness", 1},
          {"keyframes", {{"times", times}, {"values", {{"position", positions}, {"target", targets}, {"fov", fovs}}}}}};
}

// The viewer's settings (version 2 of the SuperSplat viewer schema, as splat-transform's defaults) with
// our camera and its sway.
nlohmann::json viewer_settings(const ViewerCamera& camera, double viewing_distance) {
  return {
      {"version", 2},
      {"tonemapping", "none"},
      {"highPrecisionRendering", false},
      {"background", {{"color", {0.4, 0.4, 0.4}}}},
      {"postEffectSettings",
       {{"sharpness", {{"enabled", false}, {"amount", 0}}},
        {"bloom", {{"enabled", false}, {"intensity", 1}, {"blurLevel", 2}}},
        {"grading", {{"enabled", false}, {"brightness", 0}, {"contrast", 1}, {"saturation", 1}, {"tint", {1, 1, 1}}}},
        {"vignette", {{"enabled", false}, {"intensity", 0.5}, {"inner", 0.3}, {"outer", 0.75}, {"curvature", 1}}},
        {"fringing", {{"enabled", false}, {"intensity", 0.5}}}}},
      {"animTracks", nlohmann::json::array({sway_track(camera, viewing_distance)})},
      {"cameras",
       {{{"initial",
          {{"position", to_viewer(camera.position)}, {"target", to_viewer(camera.target)}, {"fov", camera.fov_deg}}}}}},
      {"annotations", nlohmann::json::array()},
      {"startMode", "animTrack"},
  };
}

}  // namespace

SplatTransformTool splat_transform_in(const std::string& root) {
  return tool_for(fs::path(root) / kPackage);
}

SplatTransformTool find_splat_transform() {
  if (const char* given = std::getenv("ISPLAT_SPLAT_TRANSFORM")) return tool_for(given);
  return tool_for(resolve_shipped_path(kPackage));
}

std::optional<std::string> run_splat_transform(const SplatTransformTool& tool, const std::vector<std::string>& args,
                                               std::string& why) {
  if (std::system("command -v node >/dev/null 2>&1") != 0) {
    why = "node is not installed (scripts/setup.sh installs it)";
    return std::nullopt;
  }
  if (tool.cli.empty() || !fs::exists(tool.cli)) {
    const bool relative = !fs::path(tool.cli).is_absolute();
    why = cat("splat-transform is not installed: no ", tool.cli.empty() ? std::string(kPackage) : tool.cli,
              relative ? " under the working directory or the folders above the executable" : "",
              " (scripts/setup.sh installs it; ISPLAT_SPLAT_TRANSFORM overrides the path)");
    return std::nullopt;
  }
  std::string cmd = "node " + shell_quote(tool.cli);
  for (const auto& a : args) cmd += " " + shell_quote(a);
  cmd += " 2>&1";
  FILE* pipe = popen(cmd.c_str(), "r");
  ISPLAT_CHECK(pipe, "cannot start node for splat-transform");
  std::string log;
  std::array<char, 512> buf;
  while (fgets(buf.data(), buf.size(), pipe)) log += buf.data();
  const int rc = pclose(pipe);
  ISPLAT_CHECK(rc == 0, "splat-transform failed (", cmd, "):\n", log);
  return log;
}

ViewerCamera source_viewer_camera(const Gaussians& g, double fov_deg) {
  ViewerCamera camera;
  camera.fov_deg = fov_deg;
  const auto z = g.means.detach().to(torch::kFloat64).select(-1, 2).reshape({-1});
  const auto front = z.index({z > 0});
  if (front.numel() > 0) camera.target = {0, 0, front.median().item<double>()};
  return camera;
}

bool write_html_viewer(const std::string& path, const Gaussians& g, const ViewerCamera& camera,
                       const SplatTransformTool& tool, std::string& why, bool colors_linear) {
  ISPLAT_CHECK(fs::path(path).extension() == ".html", path, ": the viewer page must end in .html");
  ISPLAT_CHECK(camera.fov_deg > 0 && camera.fov_deg < 180, path, ": viewer field of view ", camera.fov_deg,
               " degrees is not in (0, 180)");
  const double gap = std::hypot(camera.target[0] - camera.position[0], camera.target[1] - camera.position[1],
                                camera.target[2] - camera.position[2]);
  ISPLAT_CHECK(gap > 0, path, ": the viewer camera's target is its own position; nothing to look along");
  ScratchDir scratch;
  const std::string ply = (scratch.path / "scene.ply").string();
  const std::string settings = (scratch.path / "settings.json").string();
  write_ply(ply, g, colors_linear);
  write_file_atomic(settings, viewer_settings(camera, gap).dump(2) + "\n");
  AtomicPath out(path);
  // -q: errors only; -w: never stop to ask about an existing file (the temporary name is ours).
  if (!run_splat_transform(tool, {"-q", "-w", "-E", settings, ply, out.temp()}, why)) return false;
  out.commit();
  return true;
}

}  // namespace isplat
