// Reader for the official Hypersim release layout (DESIGN §4): split CSV, per-scene camera model,
// keyframe poses in asset units, tonemap JPGs or HDR HDF5 colour, and ray-distance depth.
#pragma once
#include <map>
#include <string>
#include <vector>

#include "data/sequence.h"

namespace isplat {

class ConfigVisitor;

struct HypersimOptions {
  std::string root = "out/data/hypersim";
  std::string split = "train";
  std::string color = "jpg";
  std::string split_csv = "metadata_images_split_scene_v1.csv";
  std::string camera_csv = "metadata_camera_parameters.csv";
  std::vector<std::string> scenes;
  std::vector<std::string> scene_blacklist;
  int64_t min_frames = 2;
  void visit(ConfigVisitor& v);
};

struct HypersimIndex {
  std::vector<Sequence> sequences;
  int64_t frames = 0;
  std::map<std::string, int64_t> skipped;  // reason -> count of frames (or scenes, as the reason says)
  std::string summary() const;
};

// Scans the release under options.root. Frames outside the split, not in the public release, or with
// missing files are skipped and counted; a scene lacking camera parameters or metadata_scene.csv is
// skipped with its reason. Malformed CSV/HDF5 metadata throws Error naming the file.
HypersimIndex read_hypersim(const HypersimOptions& options);

// Folder and file names of the release, shared by the reader and the synthetic writer.
namespace hypersim_layout {
std::string frame_stem(int frame_id);  // "frame.0007"
std::string preview_dir(const std::string& scene_dir,
                        const std::string& camera);  // .../images/scene_cam_00_final_preview
std::string hdf5_color_dir(const std::string& scene_dir, const std::string& camera);  // .../scene_cam_00_final_hdf5
std::string geometry_dir(const std::string& scene_dir, const std::string& camera);    // .../scene_cam_00_geometry_hdf5
std::string detail_camera_dir(const std::string& scene_dir, const std::string& camera);  // .../_detail/cam_00
}  // namespace hypersim_layout

}  // namespace isplat
