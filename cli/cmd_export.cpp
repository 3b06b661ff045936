// `infinisplat export`: a PLY scene in the files other viewers open (.splat, .spz, PLY with SH degree 3, HTML).
#include <cmath>
#include <filesystem>
#include <iostream>

#include "cli/commands.h"
#include "cli/scene_camera.h"
#include "core/args.h"
#include "core/error.h"
#include "export/splat_formats.h"
#include "export/splat_transform.h"
#include "io/atomic_file.h"
#include "io/ply.h"

namespace isplat::cli {
namespace fs = std::filesystem;

namespace {
// The viewer starts at the source camera, looking along its axis at the scene's typical depth.
ViewerCamera camera_from_view(const View& view, double typical_depth) {
  const Eigen::Matrix3d R = view.T_cw.topLeftCorner<3, 3>();
  const Eigen::Vector3d centre = -R.transpose() * view.T_cw.topRightCorner<3, 1>();
  const Eigen::Vector3d target = centre + typical_depth * R.transpose().col(2);
  ViewerCamera camera;
  camera.position = {centre.x(), centre.y(), centre.z()};
  camera.target = {target.x(), target.y(), target.z()};
  // The viewer applies its field of view along the longer side of its window: take the photo's along its own.
  const bool landscape = view.intr.width >= view.intr.height;
  camera.fov_deg = 2 *
                   std::atan(landscape ? 0.5 * view.intr.width / view.intr.fx : 0.5 * view.intr.height / view.intr.fy) *
                   180 / M_PI;
  return camera;
}
}  // namespace

int run_export(int argc, char** argv) {
  std::string ply, format, out, camera_json;
  double fov = 60;
  ArgParser args("infinisplat export",
                 "Convert a Gaussian PLY for other viewers: splat (antimatter15's 32-byte web layout), spz "
                 "(Niantic's gzip format, version 2), ply-sh3 (the 3DGS PLY with all 45 f_rest_* present, as "
                 "zeros, for viewers that need SH degree 3), html (one self-contained page with PlayCanvas's "
                 "viewer, made by splat-transform through node).");
  args.option("--ply", ply, "input scene (3DGS PLY, as `predict` writes it)", "FILE");
  args.option("--format", format, "splat | spz | ply-sh3 | html", "NAME");
  args.option("--out", out, "output file (html: must end in .html)", "FILE");
  args.option("--camera", camera_json, "html: the source camera (default: <ply>.camera.json when it exists)", "FILE");
  args.option("--fov", fov, "html: field of view along the longer side, degrees, when there is no camera JSON")
      .range(1, 179, "degrees");
  args.epilog(
      "Coordinates stay in the source camera's OpenCV frame (x right, y down, z forward) for splat and "
      "ply-sh3; spz stores them as its RUB convention asks (y and z negated); the html page opens at the "
      "source camera. See README, \"Viewers and formats\".");
  if (!args.parse(argc, argv, 2)) return 0;
  ISPLAT_CHECK(!ply.empty() && !format.empty() && !out.empty(),
               "export: --ply, --format and --out are required (see --help)");
  refuse_output_over_input(
      "export", {"--out", out},
      {{"--ply", ply}, {"--camera", camera_json.empty() ? camera_sidecar_path(ply) : camera_json}});
  remove_temporaries_on_signal();  // SIGINT/SIGTERM leave no temporary of the output behind
  ErrorContext context("exporting ", ply, " as ", format, " to ", out);
  // Colours stay sRGB from file to file: no trip through linear RGB.
  const Gaussians g = read_ply(ply, /*want_linear=*/false);
  if (format == "splat") {
    write_splat(out, g, false);
  } else if (format == "spz") {
    write_spz(out, g, false);
  } else if (format == "ply-sh3") {
    PlyOptions options;
    options.sh_degree = 3;
    for (const std::string& c : read_ply_comments(ply))  // e.g. what pruning removed; the writer adds its own line
      if (c != kPlyWriterComment) options.comments.push_back(c);
    write_ply(out, g, false, options);
  } else if (format == "html") {
    ViewerCamera camera = source_viewer_camera(g, fov);
    const std::string sidecar = camera_json.empty() ? camera_sidecar_path(ply) : camera_json;
    if (!camera_json.empty() || fs::exists(sidecar)) {
      double typical_depth = 0;
      const View view = read_scene_camera(sidecar, typical_depth);
      camera = camera_from_view(view, typical_depth);
    }
    std::string why;
    if (!write_html_viewer(out, g, camera, find_splat_transform(), why, false)) fail("export: html: ", why);
  } else {
    fail("export: --format '", format, "' is not one of splat, spz, ply-sh3, html");
  }
  std::cout << "wrote " << g.count() << " Gaussians to " << fs::absolute(out).string() << " (" << format << ", "
            << fs::file_size(out) / 1e6 << " MB)\n";
  return 0;
}

}  // namespace isplat::cli
