// nerfstudio transforms.json (DL3DV, ScanNet++ exports): global or per-frame intrinsics, OpenGL
// camera-to-world matrices, optional applied_transform, depth files and resized image folders.
#pragma once
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "data/sequence.h"

namespace isplat {

// Frames sorted by file_path. Poses go to T_cw (OpenCV axes). When the file has an applied_transform
// (3x4), it is undone so poses return to the capture's original frame. Depth files: .exr planar metres,
// .png 16-bit millimetres. Missing keys or files throw Error naming the file and key.
Sequence nerfstudio_sequence(const std::string& scene_dir, const std::string& dataset,
                             const std::string& transforms_name = "transforms.json");

// Writer used by the synthetic generator: one global pinhole camera (camera_model OPENCV, zero
// distortion), frames with file_path, transform_matrix and depth_file_path, and an applied_transform.
struct NerfstudioFrameOut {
  std::string file_path;
  std::string depth_file_path;
  Pose T_cw;
};
void write_nerfstudio(const std::string& scene_dir, const Intrinsics& intr,
                      const std::vector<NerfstudioFrameOut>& frames,
                      const Eigen::Matrix4d& applied_transform = Eigen::Matrix4d::Identity());

}  // namespace isplat
