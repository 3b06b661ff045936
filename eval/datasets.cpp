// Dataset readers behind the evaluation config.
#include "eval/datasets.h"

#include <cstdio>
#include <filesystem>

#include "core/config.h"
#include "core/error.h"
#include "data/colmap.h"
#include "data/hypersim.h"
#include "data/nerfstudio.h"
#include "io/atomic_file.h"

namespace isplat {
namespace fs = std::filesystem;

void EvalDatasetOptions::visit(ConfigVisitor& v) {
  v.field("name", name, "name in manifests and reports (e.g. eth3d, dl3dv)");
  v.field("format", format, "layout of the scenes", {"colmap", "nerfstudio", "hypersim"});
  v.field("root", root, "folder holding one folder per scene (or a single scene folder)");
  v.field("scenes", scenes, "scene folders to use (empty = all)");
  v.field("width", width, "evaluation width (ETH3D 2016, ScanNet++ 1536, T&T/DL3DV 1920); 0 = native",
          Range::at_least(0));
  v.field("height", height, "evaluation height (ETH3D 1344, ScanNet++ 1024, T&T/DL3DV 1080); 0 = native",
          Range::at_least(0));
  v.field("images_dir", images_dir, "COLMAP: image folder relative to the scene");
  v.field("sparse_dir", sparse_dir, "COLMAP: model folder relative to the scene");
  v.field("depth_dir", depth_dir, "COLMAP: depth folder relative to the scene");
  v.field("depth_format", depth_format, "COLMAP: depth files", {"exr", "png16_mm", "raw_float32", "none"});
  v.field("depth_suffix", depth_suffix, "COLMAP: appended to the image stem (raw_float32: to the full name)");
  v.field("depth_replace_from", depth_replace_from, "COLMAP: substring of image names replaced in depth names");
  v.field("depth_replace_to", depth_replace_to, "COLMAP: its replacement");
  v.field("transforms", transforms, "nerfstudio: transforms file name");
  v.field("split", split, "hypersim: split to evaluate", {"train", "val", "test", "all"});
  v.field("prompts", prompts,
          "prompts for sparse (LiDAR) priors: drawn from the source depth, or the COLMAP "
          "points3D seen in the source view (real captures without a depth sensor)",
          {"depth", "points3d"});
}

namespace {
std::vector<std::string> scene_dirs(const EvalDatasetOptions& o, const std::string& marker) {
  if (!fs::is_directory(o.root)) fail("eval dataset '", o.name, "': root ", o.root, " is not a folder");
  if (fs::exists(fs::path(o.root) / marker)) return {o.root};  // a single scene
  std::vector<std::string> dirs;
  if (!o.scenes.empty()) {
    for (const auto& s : o.scenes) {
      const fs::path p = fs::path(o.root) / s;
      if (!fs::is_directory(p)) fail("eval dataset '", o.name, "': scene ", p.string(), " does not exist");
      dirs.push_back(p.string());
    }
  } else {
    for (const auto& e : fs::directory_iterator(o.root))
      if (e.is_directory()) dirs.push_back(e.path().string());
    std::sort(dirs.begin(), dirs.end());
  }
  if (dirs.empty()) fail("eval dataset '", o.name, "': no scene folders under ", o.root);
  return dirs;
}
}  // namespace

std::vector<Sequence> load_eval_dataset(const EvalDatasetOptions& o) {
  std::vector<Sequence> out;
  if (o.format == "hypersim") {
    HypersimOptions h;
    h.root = o.root;
    h.split = o.split;
    h.scenes = o.scenes;
    out = read_hypersim(h).sequences;
  } else if (o.format == "colmap") {
    ColmapSceneLayout layout;
    layout.images_dir = o.images_dir;
    layout.sparse_dir = o.sparse_dir;
    layout.depth_dir = o.depth_dir;
    layout.depth_format = o.depth_format;
    layout.depth_suffix = o.depth_suffix;
    layout.depth_replace_from = o.depth_replace_from;
    layout.depth_replace_to = o.depth_replace_to;
    for (const auto& dir : scene_dirs(o, o.sparse_dir)) out.push_back(colmap_sequence(dir, o.name, layout));
  } else if (o.format == "nerfstudio") {
    for (const auto& dir : scene_dirs(o, o.transforms)) out.push_back(nerfstudio_sequence(dir, o.name, o.transforms));
  } else {
    fail("eval dataset '", o.name, "': unknown format '", o.format, "'");
  }
  for (auto& s : out) s.dataset = o.name;
  if (out.empty()) fail("eval dataset '", o.name, "': no sequences found under ", o.root);
  return out;
}

namespace {
// FNV-1a over text: the fingerprint's hashes (as file_fingerprint's, 16 hex digits).
struct Fnv {
  uint64_t h = 14695981039346656037ull;
  Fnv& add(const std::string& s) {
    for (unsigned char c : s) h = (h ^ c) * 1099511628211ull;
    h = (h ^ 0x1f) * 1099511628211ull;  // a separator: ("ab", "c") differs from ("a", "bc")
    return *this;
  }
  Fnv& add(double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.17g", v);
    return add(std::string(b));
  }
  std::string hex() const {
    char b[17];
    std::snprintf(b, sizeof b, "%016llx", static_cast<unsigned long long>(h));
    return b;
  }
};

void add_file_stat(Fnv& f, const std::string& path, const fs::path& root) {
  if (path.empty()) return;
  f.add(fs::path(path).lexically_relative(root).string());
  std::error_code ec;
  const auto size = fs::file_size(path, ec);
  f.add(ec ? std::string("missing") : std::to_string(size));
  const auto time = fs::last_write_time(path, ec);
  f.add(ec ? std::string("-") : std::to_string(time.time_since_epoch().count()));
}
}  // namespace

nlohmann::json dataset_fingerprint(const EvalDatasetOptions& o, const std::vector<Sequence>& sequences) {
  std::error_code root_ec, ec;
  const fs::path root = fs::weakly_canonical(o.root, root_ec);
  Fnv frames, cameras, files;
  int64_t count = 0;
  for (const auto& s : sequences)
    for (const auto& fr : s.frames) {
      ++count;
      frames.add(s.id()).add(fr.name).add(fs::path(fr.image_path).lexically_relative(o.root).string());
      const Intrinsics& k = fr.view.intr;
      cameras.add(k.width).add(k.height).add(k.fx).add(k.fy).add(k.cx).add(k.cy);
      for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) cameras.add(fr.view.T_cw(r, c));
      for (double d : fr.distortion) cameras.add(d);
      add_file_stat(files, fr.image_path, o.root);
      add_file_stat(files, fr.depth_path, o.root);
    }
  nlohmann::json model = nlohmann::json::object();
  if (o.format == "colmap" || o.format == "nerfstudio") {
    const bool colmap = o.format == "colmap";
    for (const auto& dir : scene_dirs(o, colmap ? o.sparse_dir : o.transforms)) {
      std::vector<fs::path> paths;
      if (colmap) {
        for (const auto& e : fs::directory_iterator(fs::path(dir) / o.sparse_dir, ec))
          if (e.is_regular_file()) paths.push_back(e.path());
      } else {
        paths.push_back(fs::path(dir) / o.transforms);
      }
      for (const auto& p : paths)
        if (fs::is_regular_file(p, ec)) model[p.lexically_relative(o.root).string()] = file_fingerprint(p.string());
    }
  }
  return {{"root", (root_ec ? fs::path(o.root) : root).string()},
          {"frames", count},
          {"frame_list", frames.hex()},
          {"cameras", cameras.hex()},
          {"files", files.hex()},
          {"model_files", model}};
}

std::string fingerprint_changes(const nlohmann::json& before, const nlohmann::json& now) {
  std::vector<std::string> changed;
  const auto text = [](const nlohmann::json& j, const char* key) {
    return j.is_object() && j.contains(key) ? j.at(key).dump() : std::string("(none)");
  };
  if (text(before, "root") != text(now, "root"))
    changed.push_back(cat("root ", text(before, "root"), " -> ", text(now, "root")));
  if (text(before, "frame_list") != text(now, "frame_list") || text(before, "frames") != text(now, "frames"))
    changed.push_back(cat("frame list (", text(before, "frames"), " -> ", text(now, "frames"), " frames)"));
  if (text(before, "cameras") != text(now, "cameras")) changed.push_back("cameras");
  if (text(before, "files") != text(now, "files"))
    changed.push_back("image or depth files (paths, sizes or modification times)");
  const nlohmann::json none = nlohmann::json::object();
  const nlohmann::json& mb = before.is_object() && before.contains("model_files") ? before["model_files"] : none;
  const nlohmann::json& mn = now.is_object() && now.contains("model_files") ? now["model_files"] : none;
  for (const auto& [name, value] : mn.items())
    if (!mb.contains(name))
      changed.push_back(cat("model file ", name, " is new"));
    else if (mb[name] != value)
      changed.push_back(cat("model file ", name, " changed"));
  for (const auto& [name, value] : mb.items())
    if (!mn.contains(name)) changed.push_back(cat("model file ", name, " is gone"));
  std::string out;
  for (const auto& c : changed) out += (out.empty() ? "" : "; ") + c;
  return out;
}

std::vector<ColmapModel> load_eval_points3d(const EvalDatasetOptions& o) {
  ISPLAT_CHECK(o.format == "colmap", "eval dataset '", o.name, "': prompts = points3d needs format colmap");
  std::vector<ColmapModel> models;
  for (const auto& dir : scene_dirs(o, o.sparse_dir))
    models.push_back(read_colmap((fs::path(dir) / o.sparse_dir).string()));
  return models;
}

}  // namespace isplat
