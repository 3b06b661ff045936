// Dataset generation: scene building, rendering, and writing the Hypersim / COLMAP / nerfstudio layouts.
#include "data/synth/generate.h"

#include <Eigen/Geometry>
#include <filesystem>
#include <opencv2/imgproc.hpp>
#include <random>

#include "core/config.h"
#include "core/error.h"
#include "core/log.h"
#include "core/progress.h"
#include "data/colmap.h"
#include "data/hypersim.h"
#include "data/nerfstudio.h"
#include "data/synth/builder.h"
#include "data/synth/render.h"
#include "data/tuples.h"
#include "geometry/convert.h"
#include "io/atomic_file.h"
#include "io/csv.h"
#include "io/depth_io.h"
#include "io/hdf5_io.h"
#include "io/image_io.h"

namespace isplat {
namespace fs = std::filesystem;
using synth::CameraPose;
using synth::kPi;
using synth::Scene;

void GenerateOptions::visit(ConfigVisitor& v) {
  v.field("out", out, "output folder (hypersim/ and eval/ are created inside)");
  v.field("seed", seed, "seed for scene layouts and trajectories", Range::at_least(0));
  v.field("train_scenes", train_scenes, "training scenes (Hypersim layout, split 'train')", Range::at_least(0));
  v.field("val_scenes", val_scenes, "validation scenes (split 'val')", Range::at_least(0));
  v.field("test_scenes", test_scenes, "held-out test scenes (split 'test')", Range::at_least(0));
  v.field("cameras_per_scene", cameras_per_scene, "camera trajectories per training scene", Range::between(1, 9));
  v.field("frames", frames, "frames per training trajectory", Range::at_least(2));
  v.field("train_styles", train_styles,
          "styles of the Hypersim-layout scenes, cycled: room | desk | street | hall | clutter (clutter: random "
          "primitives at a random scale, for domain randomization; courtyard and atrium are the evaluation styles, and "
          "training on them would not be cross-style)");
  v.field("hfov_deg", hfov_deg,
          "[min, max] horizontal field of view of Hypersim-layout cameras in degrees, drawn per scene "
          "(Hypersim: 60)",
          Range::between(10, 150));
  v.field("room_max_step", room_max_step,
          "largest step between consecutive room frames, metres (steps are stratified on a log scale from "
          "0.04 m); 0.8 lets windows of 10 views fill the [2 m, inf) baseline bin",
          Range::between(0.05, 5.0));
  v.field("width", width, "training image width (Hypersim native is 1024)", Range::at_least(16));
  v.field("height", height, "training image height (Hypersim native is 768)", Range::at_least(16));
  v.field("supersample", supersample, "n x n colour samples per pixel (antialiasing)", Range::between(1, 4));
  v.field("tilt_shift_every", tilt_shift_every, "every k-th training scene uses a tilt-shift camera (0 = none)",
          Range::at_least(0));
  v.field("hdf5_color", hdf5_color, "also write linear HDR final_hdf5 colour (float16) besides tonemap JPGs");
  v.field("eval_datasets", eval_datasets,
          "evaluation sets: <style>_<layout>, style courtyard|atrium|room|hall (hall: a training style of the depth "
          "prior, for held-out-style checks in the evaluation sets' format), layout colmap|nerfstudio");
  v.field("eval_scenes", eval_scenes, "scenes per evaluation set", Range::at_least(0));
  v.field("eval_frames", eval_frames, "frames per evaluation sequence", Range::at_least(2));
  v.field("eval_width", eval_width, "evaluation image width", Range::at_least(16));
  v.field("eval_height", eval_height, "evaluation image height", Range::at_least(16));
}

void GenerateConfig::visit(ConfigVisitor& v) {
  v.section("runtime", "threads, seed and logging", runtime);
  v.section("generate", "the procedural dataset", generate);
}

std::string generated_hypersim_root(const std::string& out) {
  return (fs::path(out) / "hypersim").string();
}
std::string generated_eval_root(const std::string& out, const std::string& dataset) {
  return (fs::path(out) / "eval" / dataset).string();
}

namespace {

std::string scene_name(int64_t index) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "ai_%03d_%03d", static_cast<int>(index / 10 + 1), static_cast<int>(index % 10 + 1));
  return buf;
}

// The rendered float buffers are written as they are (render_frame allocates them continuous).
const float* float_pixels(const cv::Mat& m) {
  ISPLAT_CHECK(m.isContinuous() && m.depth() == CV_32F, "generate: expected a continuous float image");
  return m.ptr<float>(0);
}

// Pinhole intrinsics with the given horizontal field of view.
Intrinsics eval_intrinsics(const GenerateOptions& o, double hfov) {
  return Intrinsics::from_hfov(hfov, static_cast<int>(o.eval_width), static_cast<int>(o.eval_height));
}

Pose pose_of(const CameraPose& c) {
  return invert_pose(make_pose(c.R_wc, c.center));
}

// ---------------------------------------------------------------- Hypersim layout
struct HypersimScenePlan {
  std::string name, split, style;
  uint64_t seed;
  bool tilt_shift;
  double mpau;
  double hfov;  // radians
};

Eigen::Matrix3d camera_matrix(bool tilt_shift, double hfov, int W, int H, std::mt19937_64& rng) {
  const double a = std::tan(0.5 * hfov);  // Hypersim: a 60 degree horizontal field of view
  Eigen::Matrix3d M;
  M << a, 0, 0, 0, a * H / W, 0, 0, 0, -1;
  if (tilt_shift) {  // V-Ray tilt-shift: shifted and tilted image plane
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    M(0, 2) = 0.03 * u(rng);
    M(1, 2) = 0.04 * u(rng);
    M(2, 0) = 0.06 * u(rng);
    M(2, 1) = 0.08 * u(rng);
  }
  return M;
}

void write_hypersim(const GenerateOptions& o, ProgressBar& bar) {
  namespace L = hypersim_layout;
  const std::string root = generated_hypersim_root(o.out);
  const int W = static_cast<int>(o.width), H = static_cast<int>(o.height);
  std::vector<HypersimScenePlan> plans;
  std::mt19937_64 rng(mix_seed(static_cast<uint64_t>(o.seed), 1000));
  const double units[] = {0.0254, 0.01, 0.02};
  const int64_t total = o.train_scenes + o.val_scenes + o.test_scenes;
  ISPLAT_CHECK(!o.train_styles.empty(), "generate.train_styles is empty");
  ISPLAT_CHECK(o.hfov_deg.size() == 2 && o.hfov_deg[0] <= o.hfov_deg[1], "generate.hfov_deg must be [min, max], got ",
               o.hfov_deg.size(), " values");
  for (int64_t k = 0; k < total; ++k) {
    const std::string split = k < o.train_scenes ? "train" : k < o.train_scenes + o.val_scenes ? "val" : "test";
    // The field of view is drawn only when it varies, so the default (Hypersim's 60 degrees) keeps its draws.
    const double hfov =
        (o.hfov_deg[0] == o.hfov_deg[1] ? o.hfov_deg[0]
                                        : std::uniform_real_distribution<double>(o.hfov_deg[0], o.hfov_deg[1])(rng)) *
        kPi / 180.0;
    plans.push_back({scene_name(k), split, o.train_styles[static_cast<size_t>(k) % o.train_styles.size()],
                     mix_seed(static_cast<uint64_t>(o.seed), static_cast<uint64_t>(k)),
                     o.tilt_shift_every > 0 && k % o.tilt_shift_every == o.tilt_shift_every - 1, units[k % 3], hfov});
  }
  CsvTable split_csv;
  split_csv.header = {"scene_name",     "camera_name",         "frame_id", "included_in_public_release",
                      "exclude_reason", "split_partition_name"};
  CsvTable camera_csv;
  camera_csv.header = {"scene_name", "settings_output_img_height", "settings_output_img_width",
                       "settings_units_info_meters_scale", "use_camera_physical"};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) camera_csv.header.push_back(cat("M_cam_from_uv_", i, j));
  auto add_camera_row = [&](const std::string& scene, double mpau, bool tilt_shift, const Eigen::Matrix3d& M) {
    std::vector<std::string> row = {scene, cat(H, ".0"), cat(W, ".0"), cat(mpau), tilt_shift ? "True" : "False"};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) row.push_back(cat(std::setprecision(17), M(i, j)));
    camera_csv.rows.push_back(row);
  };

  for (size_t k = 0; k < plans.size(); ++k) {
    const auto& plan = plans[k];
    const Scene scene = synth::build_scene(plan.style, plan.seed);
    const std::string scene_dir = (fs::path(root) / plan.name).string();
    const Eigen::Matrix3d M = camera_matrix(plan.tilt_shift, plan.hfov, W, H, rng);
    add_camera_row(plan.name, plan.mpau, plan.tilt_shift, M);
    CsvTable meta;
    meta.header = {"parameter_name", "parameter_value"};
    meta.rows = {{"meters_per_asset_unit", cat(std::setprecision(17), plan.mpau)}};
    write_csv((fs::path(scene_dir) / "_detail" / "metadata_scene.csv").string(), meta);
    CsvTable cams;
    cams.header = {"camera_name"};
    for (int64_t c = 0; c < o.cameras_per_scene; ++c) cams.rows.push_back({cat("cam_0", c)});
    write_csv((fs::path(scene_dir) / "_detail" / "metadata_cameras.csv").string(), cams);

    double exposure = -1;
    for (int64_t c = 0; c < o.cameras_per_scene; ++c) {
      const std::string cam = cat("cam_0", c);
      const auto poses =
          synth::make_trajectory(scene, static_cast<int>(o.frames), mix_seed(plan.seed, 77 + c), 0.04, o.room_max_step);
      std::vector<double> orient, pos;
      std::vector<int64_t> frame_ids;
      for (size_t f = 0; f < poses.size(); ++f) {
        const Eigen::Matrix3d R_gl = poses[f].R_wc * Eigen::Vector3d(1, -1, -1).asDiagonal();
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) orient.push_back(R_gl(i, j));
        for (int i = 0; i < 3; ++i) pos.push_back(poses[f].center[i] / plan.mpau);
        frame_ids.push_back(static_cast<int64_t>(f));
        // Like the release, a few frames are flagged and not published: listed in the CSV, no files.
        const bool withheld = k == 0 && c == 0 && f == 5;
        split_csv.rows.push_back({plan.name, cam, std::to_string(f), withheld ? "False" : "True",
                                  withheld ? "CONTENT FLAGGED FOR REMOVAL" : "", withheld ? "" : plan.split});
        if (withheld) {
          bar.tick();
          continue;
        }
        const auto frame =
            synth::render_frame(scene, synth::hypersim_ray_camera(poses[f], M, W, H), static_cast<int>(o.supersample));
        if (exposure < 0) exposure = hypersim_exposure(frame.radiance, frame.hit);  // one exposure per scene
        const std::string stem = L::frame_stem(static_cast<int>(f));
        write_image((fs::path(L::preview_dir(scene_dir, cam)) / (stem + ".tonemap.jpg")).string(),
                    apply_exposure_gamma(frame.radiance, exposure), 95);
        write_hdf5((fs::path(L::geometry_dir(scene_dir, cam)) / (stem + ".depth_meters.hdf5")).string(), {H, W},
                   float_pixels(frame.distance), H5Type::Float16, 4);
        if (o.hdf5_color)
          write_hdf5((fs::path(L::hdf5_color_dir(scene_dir, cam)) / (stem + ".color.hdf5")).string(), {H, W, 3},
                     float_pixels(frame.radiance), H5Type::Float16, 4);
        bar.tick();
      }
      const std::string cam_dir = L::detail_camera_dir(scene_dir, cam);
      const int64_t n = static_cast<int64_t>(poses.size());
      write_hdf5((fs::path(cam_dir) / "camera_keyframe_orientations.hdf5").string(), {n, 3, 3}, orient.data(),
                 H5Type::Float64, 0);
      write_hdf5((fs::path(cam_dir) / "camera_keyframe_positions.hdf5").string(), {n, 3}, pos.data(), H5Type::Float64,
                 0);
      write_hdf5((fs::path(cam_dir) / "camera_keyframe_frame_indices.hdf5").string(), {n}, frame_ids.data(),
                 H5Type::Int64, 0);
    }
  }
  // A scene listed in the metadata but absent from disk, as for scenes without public images.
  for (int f = 0; f < 3; ++f)
    split_csv.rows.push_back({"ai_099_001", "cam_00", std::to_string(f), "True", "", "train"});
  add_camera_row("ai_099_001", 0.0254, false, camera_matrix(false, kPi / 3.0, W, H, rng));
  write_csv((fs::path(root) / "metadata_images_split_scene_v1.csv").string(), split_csv);
  write_csv((fs::path(root) / "metadata_camera_parameters.csv").string(), camera_csv);
}

// ---------------------------------------------------------------- evaluation layouts
struct EvalFrame {
  std::string name;
  CameraPose pose;
  synth::RenderedFrame frame;
};

ColmapModel colmap_model(const Intrinsics& intr, const std::vector<EvalFrame>& frames, uint64_t seed) {
  ColmapModel m;
  m.cameras[1] = {1, 1, intr.width, intr.height, {intr.fx, intr.fy, intr.cx, intr.cy}};
  std::vector<View> views;
  for (size_t i = 0; i < frames.size(); ++i) {
    ColmapImage img;
    img.id = static_cast<int64_t>(i) + 1;
    img.camera_id = 1;
    img.name = frames[i].name;
    const Pose T = pose_of(frames[i].pose);
    pose_to_colmap(T, img.qvec, img.tvec);
    m.images[img.id] = img;
    views.push_back({intr, T});
  }
  // Sparse points: surface samples seen in at least two views, with tracks like SfM would give.
  std::mt19937_64 rng(seed);
  int64_t next_id = 1;
  for (size_t i = 0; i < frames.size(); i += 3) {
    const cv::Mat& planar = frames[i].frame.planar;
    for (int s = 0; s < 120; ++s) {
      const int y = std::uniform_int_distribution<int>(0, planar.rows - 1)(rng);
      const int x = std::uniform_int_distribution<int>(0, planar.cols - 1)(rng);
      const float z = planar.at<float>(y, x);
      if (!std::isfinite(z)) continue;
      const Eigen::Vector3d X = views[i].backproject(x + 0.5, y + 0.5, z);
      ColmapPoint p;
      p.id = next_id;
      p.xyz = X;
      const cv::Vec3f c = frames[i].frame.radiance.at<cv::Vec3f>(y, x);
      for (int k = 0; k < 3; ++k)
        p.rgb[k] = static_cast<uint8_t>(std::clamp(std::pow(c[k], 1 / 2.2) * 255.0, 0.0, 255.0));
      p.error = 0.5;
      for (size_t j = 0; j < frames.size(); ++j) {
        Eigen::Vector2d uv;
        double zj = 0;
        if (!views[j].project(X, uv, zj)) continue;
        const int u = static_cast<int>(uv.x()), v = static_cast<int>(uv.y());
        if (u < 0 || v < 0 || u >= intr.width || v >= intr.height) continue;
        const float dj = frames[j].frame.planar.at<float>(v, u);
        if (!std::isfinite(dj) || std::fabs(dj - zj) > 0.02 * zj) continue;  // occluded in view j
        ColmapImage& img = m.images[static_cast<int64_t>(j) + 1];
        p.track.emplace_back(img.id, static_cast<int64_t>(img.xys.size()));
        img.xys.push_back(uv);
        img.point3D_ids.push_back(p.id);
      }
      if (p.track.size() < 2) {  // keep the keypoints, but without a 3D point
        for (const auto& t : p.track) m.images[t.first].point3D_ids[t.second] = -1;
        continue;
      }
      m.points[next_id++] = p;
    }
  }
  return m;
}

void write_eval_scene(const GenerateOptions& o, const std::string& dataset, const std::string& style,
                      const std::string& layout, int64_t index, ProgressBar& bar) {
  const uint64_t seed =
      mix_seed(static_cast<uint64_t>(o.seed) + 5000, static_cast<uint64_t>(index) + 31 * dataset.size());
  const Scene scene = synth::build_scene(style, seed);
  const std::string dir = (fs::path(generated_eval_root(o.out, dataset)) / cat("scene_", index)).string();
  const Intrinsics intr = eval_intrinsics(o, style == "courtyard" ? 70.0 * kPi / 180 : 65.0 * kPi / 180);
  const double max_step = style == "room" ? o.room_max_step : 0.9;  // open scenes: more pairs in [2 m, inf)
  const auto poses = synth::make_trajectory(scene, static_cast<int>(o.eval_frames), mix_seed(seed, 3), 0.04, max_step);
  std::vector<EvalFrame> frames;
  double exposure = -1;
  std::vector<NerfstudioFrameOut> ns_frames;
  for (size_t f = 0; f < poses.size(); ++f) {
    EvalFrame ef;
    ef.pose = poses[f];
    ef.frame = synth::render_frame(scene, synth::pinhole_ray_camera(poses[f], intr), static_cast<int>(o.supersample));
    if (exposure < 0) exposure = hypersim_exposure(ef.frame.radiance, ef.frame.hit);  // fixed exposure per scene
    const cv::Mat rgb = apply_exposure_gamma(ef.frame.radiance, exposure);
    char name[64];
    if (layout == "colmap") {
      std::snprintf(name, sizeof name, "IMG_%04d.jpg", static_cast<int>(f));
      ef.name = name;
      write_image((fs::path(dir) / "images" / ef.name).string(), rgb, 95);
      write_depth_exr((fs::path(dir) / "depth" / fs::path(ef.name).replace_extension(".exr")).string(),
                      ef.frame.planar);
    } else {
      std::snprintf(name, sizeof name, "frame_%05d.png", static_cast<int>(f) + 1);
      ef.name = name;
      write_image((fs::path(dir) / "images" / ef.name).string(), rgb);
      cv::Mat mm(ef.frame.planar.size(), CV_16UC1);
      for (int i = 0; i < mm.rows; ++i)
        for (int j = 0; j < mm.cols; ++j) {
          const float z = ef.frame.planar.at<float>(i, j);
          mm.at<uint16_t>(i, j) =
              std::isfinite(z) ? static_cast<uint16_t>(std::clamp(std::lround(z * 1000.0), 1L, 65535L)) : 0;
        }
      write_png16((fs::path(dir) / "depths" / ef.name).string(), mm);
      ns_frames.push_back({"images/" + ef.name, "depths/" + ef.name, pose_of(poses[f])});
    }
    frames.push_back(std::move(ef));
    bar.tick();
  }
  if (layout == "colmap") {
    const ColmapModel model = colmap_model(intr, frames, seed);
    const std::string sparse = (fs::path(dir) / "sparse" / "0").string();
    write_colmap_text(sparse, model);
    write_colmap_binary(sparse, model);
  } else {
    Eigen::Matrix4d applied = Eigen::Matrix4d::Identity();  // nerfstudio's usual axis swap
    applied.topLeftCorner<3, 3>() << 0, 1, 0, 1, 0, 0, 0, 0, -1;
    write_nerfstudio(dir, intr, ns_frames, applied);
  }
}

}  // namespace

void generate_datasets(const GenerateOptions& o) {
  struct EvalSet {
    std::string name, style, layout;
  };
  std::vector<EvalSet> eval_sets;
  for (const auto& d : o.eval_datasets) {
    const auto us = d.find('_');
    const std::string style = d.substr(0, us), layout = us == std::string::npos ? "" : d.substr(us + 1);
    if ((style != "courtyard" && style != "atrium" && style != "room" && style != "hall") ||
        (layout != "colmap" && layout != "nerfstudio"))
      fail("generate.eval_datasets: '", d, "' must be <courtyard|atrium|room|hall>_<colmap|nerfstudio>");
    eval_sets.push_back({d, style, layout});
  }
  const int64_t train_frames = (o.train_scenes + o.val_scenes + o.test_scenes) * o.cameras_per_scene * o.frames;
  const int64_t eval_frames = static_cast<int64_t>(eval_sets.size()) * o.eval_scenes * o.eval_frames;
  log_info("generate: ", o.train_scenes + o.val_scenes + o.test_scenes, " Hypersim-layout scenes (", train_frames,
           " frames at ", o.width, "x", o.height, ") and ", eval_sets.size(), " evaluation sets (", eval_frames,
           " frames) into ", o.out);
  ProgressBar bar("generate", train_frames + eval_frames, "frame");
  write_hypersim(o, bar);
  for (const auto& e : eval_sets)
    for (int64_t s = 0; s < o.eval_scenes; ++s) write_eval_scene(o, e.name, e.style, e.layout, s, bar);
  bar.finish();
  log_info("generate: done in ", ProgressBar::format_duration(bar.elapsed_seconds()), "; Hypersim root ",
           generated_hypersim_root(o.out), ", evaluation sets under ", (fs::path(o.out) / "eval").string());
}

}  // namespace isplat
