// Evaluation datasets by config: COLMAP (ETH3D, Tanks and Temples, ScanNet++), nerfstudio (DL3DV,
// ScanNet++) and Hypersim scenes, each read into frame sequences.
#pragma once
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "data/colmap.h"
#include "data/sequence.h"

namespace isplat {

class ConfigVisitor;

struct EvalDatasetOptions {
  std::string name = "dataset";
  std::string format = "colmap";    // colmap | nerfstudio | hypersim
  std::string root;                 // folder of scene folders (or one scene folder)
  std::vector<std::string> scenes;  // empty = every scene folder under root
  int64_t width = 0, height = 0;    // evaluation size (DESIGN §5); 0 = the images' own size
  // COLMAP layout (ETH3D: images_dir "images", sparse_dir "dslr_calibration_undistorted",
  // depth_dir "ground_truth_depth", depth_format "raw_float32", depth_suffix "", replace
  // "dslr_images_undistorted" -> "dslr_images").
  std::string images_dir = "images";
  std::string sparse_dir = "sparse/0";
  std::string depth_dir = "depth";
  std::string depth_format = "exr";
  std::string depth_suffix = ".exr";
  std::string depth_replace_from, depth_replace_to;
  std::string transforms = "transforms.json";  // nerfstudio
  std::string split = "test";                  // hypersim split
  std::string prompts = "depth";               // sparse prompts for LiDAR variants: depth | points3d (COLMAP)
  void visit(ConfigVisitor& v);
};

// All sequences of the dataset, scenes sorted by name. Errors name the dataset and the offending file.
std::vector<Sequence> load_eval_dataset(const EvalDatasetOptions& options);

// The COLMAP model of each sequence of a colmap dataset, in load_eval_dataset's order: the source of
// points3D prompts (prompts = points3d).
std::vector<ColmapModel> load_eval_points3d(const EvalDatasetOptions& options);

// What a manifest and the scores on it were computed from: the root (canonical path), the frame list, the cameras
// as read, each frame's image and depth file (relative path, size, modification time: one hash) and the model
// files (COLMAP sparse folder, nerfstudio transforms: size and content hash each).
nlohmann::json dataset_fingerprint(const EvalDatasetOptions& options, const std::vector<Sequence>& sequences);
// What differs between two fingerprints, in words ("root /a -> /b; frame list (32 -> 24 frames); ..."), or "" when
// nothing does.
std::string fingerprint_changes(const nlohmann::json& before, const nlohmann::json& now);

}  // namespace isplat
