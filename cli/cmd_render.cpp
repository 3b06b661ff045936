// `infinisplat render`: novel views of a PLY along an orbit, a dolly or a camera-path file, as PNG
// frames and an MP4, optionally with depth and normal visualizations.
#include <filesystem>
#include <iostream>
#include <memory>

#include <torch/torch.h>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "cli/commands.h"
#include "cli/scene_camera.h"
#include "core/args.h"
#include "core/error.h"
#include "core/log.h"
#include "core/progress.h"
#include "core/runtime.h"
#include "geometry/camera_torch.h"
#include "geometry/color.h"
#include "geometry/trajectory.h"
#include "io/atomic_file.h"
#include "io/image_io.h"
#include "io/ply.h"
#include "io/tensor_image.h"
#include "render/render.h"

namespace isplat::cli {
namespace fs = std::filesystem;

namespace {
// Expected depth / alpha, colour-mapped over [near, far] (turbo), black where nothing was hit.
cv::Mat depth_visual(const RenderOutput& r, double near, double far) {
  auto d = (r.depth[0] / torch::clamp_min(r.alpha[0], 1e-4)).contiguous();
  cv::Mat m = tensor_to_map(d), u8, color;
  m = (m - near) / std::max(1e-6, far - near);
  m.convertTo(u8, CV_8U, 255.0);
  cv::applyColorMap(u8, color, cv::COLORMAP_TURBO);
  color.setTo(cv::Scalar::all(0), tensor_to_map(r.alpha[0]) < 0.5f);
  cv::Mat rgb;
  cv::cvtColor(color, rgb, cv::COLOR_BGR2RGB);
  return rgb;
}
}  // namespace

int run_render(int argc, char** argv) {
  std::string ply, trajectory = "orbit", out, camera_json;
  int64_t frames = 60, fps = 30, width = 0, height = 0, threads = 0;
  double hfov = 60, radius = 0.08;
  bool depth = false, normal = false, no_video = false, strip = false;
  ArgParser args("infinisplat render",
                 "Render novel views of a Gaussian PLY: an orbit around the source view, a dolly "
                 "along its axis, or a camera path (JSON). Writes PNG frames and an MP4.");
  args.option("--ply", ply, "scene to render (3DGS PLY)", "FILE");
  args.option("--trajectory", trajectory, "orbit | dolly | a camera-path JSON file", "PATH");
  args.option("--out", out, "output folder", "DIR");
  args.option("--camera", camera_json, "source camera JSON (default: <ply>.camera.json from predict)", "FILE");
  args.option("--frames", frames, "frames for orbit/dolly").range(1, 100000);
  args.option("--fps", fps, "video frame rate").range(1, 1000);
  args.option("--width", width, "render width, with --height (default: the source camera's)").range(1, 65536, "pixels");
  args.option("--height", height, "render height, with --width").range(1, 65536, "pixels");
  args.option("--hfov", hfov, "horizontal field of view when there is no camera JSON, degrees")
      .range(1, 179, "degrees");
  args.option("--radius", radius, "orbit radius as a fraction of the scene depth").range(0, 10);
  args.flag("--depth", depth, "also write depth visualizations");
  args.flag("--normal", normal, "also write normal visualizations");
  args.flag("--no-video", no_video, "PNG frames only");
  args.flag("--strip", strip,
            "also write a side-by-side strip per frame (RGB | depth | normals | alpha); the video shows the strips");
  args.option("--threads", threads, "threads (0 = all cores)").range(0, kMaxThreads);
  if (!args.parse(argc, argv, 2)) return 0;
  ISPLAT_CHECK(!ply.empty() && !out.empty(), "render: --ply and --out are required (see --help)");
  ISPLAT_CHECK((width > 0) == (height > 0), "render: give --width and --height together (got ", width, "x", height,
               ")");
  // The same limit as every reader and predict: a 60000x60000 frame is gigabytes per output plane.
  ISPLAT_CHECK(width <= max_image_pixels() / std::max<int64_t>(1, height), "render: --width x --height = ", width, "x",
               height, " is above runtime.max_image_pixels (", max_image_pixels(), ")");
  configure_threads(threads);
  const Gaussians g = read_ply(ply, true);
  ISPLAT_CHECK(g.count() > 0, ply, ": no Gaussians to render");
  double typical_depth = 0;
  View base;
  const std::string cam_path = camera_json.empty() ? camera_sidecar_path(ply) : camera_json;
  if (fs::exists(cam_path)) {
    base = read_scene_camera(cam_path, typical_depth);
  } else {
    ISPLAT_CHECK(camera_json.empty(), camera_json, ": no such file");
    base = {Intrinsics::from_hfov(hfov * M_PI / 180.0, width ? int(width) : 512, height ? int(height) : 384),
            Pose::Identity()};
    typical_depth = g.means.select(1, 2).median().item<double>();  // the camera sits at the origin
    log_info("render: no camera JSON beside ", ply, "; using a ", hfov, " degree camera at the origin");
  }
  if (width > 0 && height > 0) base.intr = base.intr.resized(static_cast<int>(width), static_cast<int>(height));
  ISPLAT_CHECK(typical_depth > 0, "render: ", ply, ": cannot size the camera motion (typical depth ", typical_depth,
               "; the Gaussians lie behind the camera)");
  CameraPath path;
  if (trajectory == "orbit")
    path = orbit_path(base, typical_depth, static_cast<int>(frames), radius);
  else if (trajectory == "dolly")
    path = dolly_path(base, typical_depth, static_cast<int>(frames));
  else
    path = load_camera_path(trajectory, base);

  {  // No file render writes may be one of its inputs (a PLY or camera kept in the output folder).
    const std::vector<NamedPath> inputs = {
        {"--ply", ply},
        {"--camera", cam_path},
        {"--trajectory", trajectory == "orbit" || trajectory == "dolly" ? "" : trajectory}};
    refuse_output_over_input("render", {"--out", out}, inputs);
    std::vector<std::string> names = {"video.mp4"};
    for (size_t i = 0; i < path.views.size(); ++i)
      for (const char* kind : {"frame", "depth", "normal", "strip"}) {
        char name[64];
        std::snprintf(name, sizeof name, "%s_%04zu.png", kind, i);
        names.push_back(name);
      }
    for (const auto& name : names)
      refuse_output_over_input("render", {"--out", (fs::path(out) / name).string()}, inputs);
  }
  {
    std::error_code ec;
    fs::create_directories(out, ec);
    if (ec) fail("render: --out ", out, ": cannot create the folder: ", ec.message());
  }
  // The first SIGINT/SIGTERM stops after the frame being drawn and finishes the video with the frames so far; a
  // second one ends at once, removing the temporaries (the video's among them).
  remove_temporaries_on_signal(/*graceful=*/true);
  cv::VideoWriter video;
  const std::string video_path = (fs::path(out) / "video.mp4").string();
  // Encoded into a temporary and renamed when finalized: an interrupted render never leaves a video.mp4 without
  // its index (moov) that no player opens.
  std::unique_ptr<AtomicPath> video_file;
  const int W = path.views[0].intr.width, H = path.views[0].intr.height;
  if (!no_video) {
    video_file = std::make_unique<AtomicPath>(video_path);
    video.open(video_file->temp(), cv::VideoWriter::fourcc('m', 'p', '4', 'v'), static_cast<double>(fps),
               cv::Size(strip ? 4 * W : W, H));
    if (!video.isOpened()) {
      log_warn("render: OpenCV cannot write MP4 here (", video_path, "); writing PNG frames only");
      no_video = true;
    }
  }
  ISPLAT_CHECK(W <= max_image_pixels() / H, "render: ", cam_path, ": frames of ", W, "x", H,
               " are above runtime.max_image_pixels (", max_image_pixels(), ")");
  ErrorContext context("rendering ", ply, " at ", W, "x", H, " into ", out);
  ProgressBar bar("render", static_cast<int64_t>(path.views.size()), "frame");
  double total_ms = 0;
  size_t drawn = 0;
  for (size_t i = 0; i < path.views.size() && !interrupt_signal(); ++i, ++drawn) {
    const View& v = path.views[i];
    ISPLAT_CHECK(v.intr.width == W && v.intr.height == H, "render: ", trajectory, ": frame ", i, " is ", v.intr.width,
                 "x", v.intr.height, " but frame 0 is ", W, "x", H, "; all frames of a path share one size");
    const auto t0 = std::chrono::steady_clock::now();
    torch::NoGradGuard ng;
    const RenderOutput r = render(g, to_camera(v));
    total_ms += ms_since(t0);
    const cv::Mat rgb = tensor_to_image(torch::clamp(linear_to_srgb(torch::clamp(r.rgb, 0.0, 1.0)), 0.0, 1.0));
    char name[64];
    std::snprintf(name, sizeof name, "frame_%04zu.png", i);
    write_image((fs::path(out) / name).string(), rgb);
    const cv::Mat depth_rgb = depth || strip ? depth_visual(r, 0.3 * typical_depth, 2.5 * typical_depth) : cv::Mat();
    cv::Mat normal_rgb;
    if (normal || strip) {
      auto n = (r.normal / torch::clamp_min(r.alpha, 1e-4) * 0.5 + 0.5) * (r.alpha > 0.5);
      normal_rgb = tensor_to_image(torch::clamp(n, 0.0, 1.0));
    }
    if (depth) {
      std::snprintf(name, sizeof name, "depth_%04zu.png", i);
      write_image((fs::path(out) / name).string(), depth_rgb);
    }
    if (normal) {
      std::snprintf(name, sizeof name, "normal_%04zu.png", i);
      write_image((fs::path(out) / name).string(), normal_rgb);
    }
    cv::Mat frame = rgb;
    if (strip) {  // one image per frame, the same for the video: RGB | depth | normals | alpha
      cv::Mat depth_f, alpha;
      depth_rgb.convertTo(depth_f, CV_32FC3, 1.0 / 255.0);
      cv::cvtColor(tensor_to_map(torch::clamp(r.alpha[0], 0.0, 1.0).contiguous()), alpha, cv::COLOR_GRAY2RGB);
      cv::hconcat(std::vector<cv::Mat>{rgb, depth_f, normal_rgb, alpha}, frame);
      std::snprintf(name, sizeof name, "strip_%04zu.png", i);
      write_image((fs::path(out) / name).string(), frame);
    }
    if (!no_video) video.write(rgb_to_bgr8(frame, video_path));
    bar.tick();
  }
  bar.finish();
  if (!no_video) {
    video.release();  // writes the index: the file plays
    if (drawn > 0) video_file->commit();
  }
  std::cout << "rendered " << drawn << " frames of " << g.count() << " Gaussians at " << W << "x" << H << " ("
            << std::fixed << std::setprecision(1) << total_ms / std::max<size_t>(1, drawn) << " ms per frame)\n";
  std::cout << "wrote    " << fs::absolute(out).string() << (no_video || drawn == 0 ? "" : " (frames + video.mp4)")
            << "\n";
  if (const int sig = interrupt_signal()) {
    log_warn("render: interrupted (signal ", sig, ") after ", drawn, " of ", path.views.size(), " frames; ",
             no_video    ? std::string("no video was asked for")
             : drawn > 0 ? cat(video_path, " holds those ", drawn, " frames and plays")
                         : cat("no frame was drawn, so no ", video_path, " was written"));
    return 128 + sig;
  }
  return 0;
}

}  // namespace isplat::cli
