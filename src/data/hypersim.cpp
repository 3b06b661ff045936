// Hypersim release reader: metadata CSVs, keyframe HDF5s, and per-frame file records.
#include "data/hypersim.h"

#include <filesystem>
#include <set>

#include "core/config.h"
#include "core/error.h"
#include "core/log.h"
#include "core/runtime.h"
#include "io/csv.h"
#include "io/hdf5_io.h"

namespace isplat {
namespace fs = std::filesystem;

void HypersimOptions::visit(ConfigVisitor& v) {
  v.field("root", root, "folder holding the ai_VVV_NNN scene folders and the metadata CSVs");
  v.field("split", split, "which split_partition_name to read", {"train", "val", "test", "all"});
  v.field("color", color, "colour source: tonemap JPG previews, or HDR final_hdf5 with Hypersim's tone map",
          {"jpg", "hdf5"});
  v.field("split_csv", split_csv, "split CSV, relative to root (official: metadata_images_split_scene_v1.csv)");
  v.field("camera_csv", camera_csv, "per-scene camera parameters CSV, relative to root");
  v.field("scenes", scenes, "read only these scenes (empty = every scene in the split)");
  v.field("scene_blacklist", scene_blacklist, "scenes to leave out (e.g. known-bad scenes)");
  v.field("min_frames", min_frames, "drop camera trajectories with fewer usable frames", Range::at_least(1));
}

namespace hypersim_layout {
std::string frame_stem(int frame_id) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "frame.%04d", frame_id);
  return buf;
}
std::string preview_dir(const std::string& scene_dir, const std::string& camera) {
  return (fs::path(scene_dir) / "images" / ("scene_" + camera + "_final_preview")).string();
}
std::string hdf5_color_dir(const std::string& scene_dir, const std::string& camera) {
  return (fs::path(scene_dir) / "images" / ("scene_" + camera + "_final_hdf5")).string();
}
std::string geometry_dir(const std::string& scene_dir, const std::string& camera) {
  return (fs::path(scene_dir) / "images" / ("scene_" + camera + "_geometry_hdf5")).string();
}
std::string detail_camera_dir(const std::string& scene_dir, const std::string& camera) {
  return (fs::path(scene_dir) / "_detail" / camera).string();
}
}  // namespace hypersim_layout

std::string HypersimIndex::summary() const {
  std::string s = cat(sequences.size(), " trajectories, ", frames, " frames");
  if (!skipped.empty()) {
    s += " (skipped:";
    bool first = true;
    for (const auto& [reason, n] : skipped) {
      s += cat(first ? " " : "; ", n, " ", reason);
      first = false;
    }
    s += ")";
  }
  return s;
}

namespace {

struct SceneCamera {
  int width = 0, height = 0;
  Eigen::Matrix3d M;
};

std::map<std::string, SceneCamera> read_camera_parameters(const std::string& path) {
  const CsvTable t = read_csv(path);
  std::map<std::string, SceneCamera> out;
  for (size_t r = 0; r < t.size(); ++r) {
    SceneCamera c;
    const double w = t.number(r, "settings_output_img_width"), h = t.number(r, "settings_output_img_height");
    if (!(w >= 1 && h >= 1 && w * h <= static_cast<double>(max_image_pixels())))
      fail(path, ": data row ", r + 1, ": image size ", w, "x", h,
           " is not positive or above runtime.max_image_pixels");
    c.width = static_cast<int>(w), c.height = static_cast<int>(h);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) c.M(i, j) = t.number(r, cat("M_cam_from_uv_", i, j));
    out[t.cell(r, "scene_name")] = c;
  }
  return out;
}

double read_meters_per_asset_unit(const std::string& path) {
  const CsvTable t = read_csv(path);
  for (size_t r = 0; r < t.size(); ++r)
    if (t.cell(r, "parameter_name") == "meters_per_asset_unit") {
      const double v = t.number(r, "parameter_value");
      if (!(v > 0)) fail(path, ": meters_per_asset_unit must be positive, got ", v);
      return v;
    }
  fail(path, ": no meters_per_asset_unit row");
}

struct Keyframes {
  std::vector<Eigen::Matrix3d> R;
  std::vector<Eigen::Vector3d> p;
  std::map<int, size_t> frame_to_key;
};

Keyframes read_keyframes(const std::string& cam_dir) {
  const std::string opath = (fs::path(cam_dir) / "camera_keyframe_orientations.hdf5").string();
  const std::string ppath = (fs::path(cam_dir) / "camera_keyframe_positions.hdf5").string();
  const auto o = read_hdf5_double(opath);
  const auto p = read_hdf5_double(ppath);
  if (o.shape.size() != 3 || o.shape[1] != 3 || o.shape[2] != 3) fail(opath, ": expected shape [N, 3, 3]");
  if (p.shape.size() != 2 || p.shape[1] != 3) fail(ppath, ": expected shape [N, 3]");
  if (o.shape[0] != p.shape[0]) fail(ppath, ": ", p.shape[0], " positions but ", o.shape[0], " orientations");
  Keyframes k;
  for (int64_t n = 0; n < o.shape[0]; ++n) {
    Eigen::Matrix3d R;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) R(i, j) = o.values[n * 9 + i * 3 + j];
    k.R.push_back(R);
    k.p.emplace_back(p.values[n * 3], p.values[n * 3 + 1], p.values[n * 3 + 2]);
    if (!R.allFinite() || !k.p.back().allFinite()) fail(opath, ": keyframe ", n, " has a pose that is not finite");
  }
  const std::string ipath = (fs::path(cam_dir) / "camera_keyframe_frame_indices.hdf5").string();
  if (fs::exists(ipath)) {
    const auto idx = read_hdf5_int(ipath);
    if (idx.numel() != o.shape[0]) fail(ipath, ": ", idx.numel(), " indices for ", o.shape[0], " keyframes");
    for (size_t n = 0; n < idx.values.size(); ++n) k.frame_to_key[static_cast<int>(idx.values[n])] = n;
  } else {
    for (size_t n = 0; n < k.R.size(); ++n) k.frame_to_key[static_cast<int>(n)] = n;
  }
  return k;
}

}  // namespace

HypersimIndex read_hypersim(const HypersimOptions& opt) {
  namespace L = hypersim_layout;
  if (!fs::is_directory(opt.root))
    fail(opt.root, ": Hypersim root folder does not exist (config key data.hypersim.root)");
  const std::string split_path = (fs::path(opt.root) / opt.split_csv).string();
  const CsvTable split = read_csv(split_path);
  const std::string camera_path = (fs::path(opt.root) / opt.camera_csv).string();
  const auto cameras = read_camera_parameters(camera_path);

  const int c_scene = split.require_column("scene_name"), c_cam = split.require_column("camera_name"),
            c_frame = split.require_column("frame_id"), c_pub = split.require_column("included_in_public_release"),
            c_part = split.require_column("split_partition_name");
  const std::set<std::string> only(opt.scenes.begin(), opt.scenes.end());
  const std::set<std::string> black(opt.scene_blacklist.begin(), opt.scene_blacklist.end());

  // scene -> camera -> frame ids, in CSV order
  std::map<std::string, std::map<std::string, std::vector<int>>> wanted;
  HypersimIndex index;
  for (size_t r = 0; r < split.size(); ++r) {
    const auto& row = split.rows[r];
    const std::string& scene = row[c_scene];
    if (opt.split != "all" && row[c_part] != opt.split) continue;
    if (!only.empty() && !only.count(scene)) continue;
    if (black.count(scene)) {
      ++index.skipped["frames in blacklisted scenes"];
      continue;
    }
    if (!split.boolean(r, split.header[c_pub])) {
      ++index.skipped["frames not in the public release"];
      continue;
    }
    const double fid = split.number(r, split.header[c_frame]);
    if (!(fid >= 0 && fid < 1e9)) fail(split_path, ": data row ", r + 1, ": frame_id ", fid, " is not a frame index");
    wanted[scene][row[c_cam]].push_back(static_cast<int>(fid));
  }

  for (const auto& [scene, cams] : wanted) {
    const std::string scene_dir = (fs::path(opt.root) / scene).string();
    int64_t scene_frames = 0;
    for (const auto& c : cams) scene_frames += static_cast<int64_t>(c.second.size());
    auto cam_it = cameras.find(scene);
    if (cam_it == cameras.end()) {
      log_warn("hypersim: scene ", scene, " has no row in ", camera_path, "; skipped");
      index.skipped["frames of scenes without camera parameters"] += scene_frames;
      continue;
    }
    const std::string meta = (fs::path(scene_dir) / "_detail" / "metadata_scene.csv").string();
    if (!fs::exists(meta)) {
      index.skipped["frames of scenes without files (no _detail/metadata_scene.csv)"] += scene_frames;
      continue;
    }
    const double mpau = read_meters_per_asset_unit(meta);
    auto model = std::make_shared<HypersimCamera>(
        hypersim_camera(cam_it->second.M, cam_it->second.width, cam_it->second.height));
    for (const auto& [camera, frame_ids] : cams) {
      const std::string cam_dir = L::detail_camera_dir(scene_dir, camera);
      if (!fs::exists(fs::path(cam_dir) / "camera_keyframe_orientations.hdf5")) {
        index.skipped["frames of trajectories without keyframe files"] += static_cast<int64_t>(frame_ids.size());
        continue;
      }
      const Keyframes keys = read_keyframes(cam_dir);
      Sequence seq;
      seq.dataset = "hypersim";
      seq.scene = scene;
      seq.name = camera;
      seq.hypersim = model;
      for (int fid : frame_ids) {
        auto key = keys.frame_to_key.find(fid);
        if (key == keys.frame_to_key.end()) {
          ++index.skipped["frames without a keyframe pose"];
          continue;
        }
        FrameRecord f;
        f.name = cat(scene, "/", camera, "/", L::frame_stem(fid));
        if (opt.color == "jpg") {
          f.image_path = (fs::path(L::preview_dir(scene_dir, camera)) / (L::frame_stem(fid) + ".tonemap.jpg")).string();
        } else {
          f.image_path =
              (fs::path(L::hdf5_color_dir(scene_dir, camera)) / (L::frame_stem(fid) + ".color.hdf5")).string();
          f.color = ColorSource::HypersimHdf5;
        }
        f.depth_path =
            (fs::path(L::geometry_dir(scene_dir, camera)) / (L::frame_stem(fid) + ".depth_meters.hdf5")).string();
        f.depth = DepthSource::HypersimRayHdf5;
        if (!fs::exists(f.image_path) || !fs::exists(f.depth_path)) {
          ++index.skipped["frames with missing image or depth files"];
          continue;
        }
        f.view.intr = model->intr;
        f.view.T_cw = pose_from_hypersim(keys.R[key->second], keys.p[key->second], mpau, *model);
        seq.frames.push_back(std::move(f));
      }
      if (static_cast<int64_t>(seq.frames.size()) < opt.min_frames) {
        index.skipped[cat("frames of trajectories shorter than ", opt.min_frames)] +=
            static_cast<int64_t>(seq.frames.size());
        continue;
      }
      index.frames += static_cast<int64_t>(seq.frames.size());
      index.sequences.push_back(std::move(seq));
    }
  }
  log_info("hypersim: ", opt.root, " split '", opt.split, "': ", index.summary());
  return index;
}

}  // namespace isplat
