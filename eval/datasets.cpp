// Dataset readers behind the evaluation config.
#include "eval/datasets.h"

#include <filesystem>

#include "core/config.h"
#include "core/error.h"
#include "data/colmap.h"
#include "data/hypersim.h"
#include "data/nerfstudio.h"

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

std::vector<ColmapModel> load_eval_points3d(const EvalDatasetOptions& o) {
  ISPLAT_CHECK(o.format == "colmap", "eval dataset '", o.name, "': prompts = points3d needs format colmap");
  std::vector<ColmapModel> models;
  for (const auto& dir : scene_dirs(o, o.sparse_dir))
    models.push_back(read_colmap((fs::path(dir) / o.sparse_dir).string()));
  return models;
}

}  // namespace isplat
