// COLMAP sparse models (cameras / images / points3D) in text and binary form, read and written, and
// their conversion to a frame Sequence.
#pragma once
#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "data/sequence.h"

namespace isplat {

struct ColmapCamera {
  int64_t id = 0;
  int model_id = 1;  // PINHOLE
  int64_t width = 0, height = 0;
  std::vector<double> params;
};

struct ColmapImage {
  int64_t id = 0;
  Eigen::Vector4d qvec = Eigen::Vector4d(1, 0, 0, 0);  // w, x, y, z (world -> camera)
  Eigen::Vector3d tvec = Eigen::Vector3d::Zero();
  int64_t camera_id = 0;
  std::string name;
  std::vector<Eigen::Vector2d> xys;
  std::vector<int64_t> point3D_ids;  // -1 where a keypoint has no 3D point
};

struct ColmapPoint {
  int64_t id = 0;
  Eigen::Vector3d xyz = Eigen::Vector3d::Zero();
  std::array<uint8_t, 3> rgb{{0, 0, 0}};
  double error = 0;
  std::vector<std::pair<int64_t, int64_t>> track;  // (image_id, point2D_idx)
};

struct ColmapModel {
  std::map<int64_t, ColmapCamera> cameras;
  std::map<int64_t, ColmapImage> images;
  std::map<int64_t, ColmapPoint> points;
};

// The camera model table by id: name and parameter count (COLMAP's src/colmap/sensor/models.h).
struct ColmapModelInfo {
  int id;
  const char* name;
  int num_params;
};
const ColmapModelInfo* colmap_model_by_id(int id);
const ColmapModelInfo* colmap_model_by_name(const std::string& name);

// Reads `dir` holding cameras/images/points3D as .bin (preferred when present) or .txt. Errors name the
// file and line (text) or byte offset (binary).
ColmapModel read_colmap(const std::string& dir);
ColmapModel read_colmap_text(const std::string& dir);
ColmapModel read_colmap_binary(const std::string& dir);
void write_colmap_text(const std::string& dir, const ColmapModel& model);
void write_colmap_binary(const std::string& dir, const ColmapModel& model);

// Pinhole intrinsics of a camera plus OpenCV distortion coefficients (k1 k2 p1 p2 [k3 k4 k5 k6]), empty
// when the model has none or they are all zero. Fisheye and other non-OpenCV models with non-zero
// distortion throw Error naming the camera and model.
Intrinsics colmap_intrinsics(const ColmapCamera& camera, std::vector<double>& distortion);

// Options for turning a COLMAP scene folder into a sequence.
struct ColmapSceneLayout {
  std::string images_dir = "images";
  std::string sparse_dir = "sparse/0";               // falls back to "sparse" when absent
  std::string depth_dir = "depth";                   // relative to the scene; may be absent
  std::string depth_format = "exr";                  // exr | png16_mm | raw_float32
  std::string depth_suffix = ".exr";                 // appended to the image name's stem (raw: to the full name)
  std::string depth_replace_from, depth_replace_to;  // rewrite of the image name for its depth file (ETH3D)
  bool allow_undistort = true;                       // undistort OpenCV-model images, else reject them
};

// Images sorted by name form the sequence; a missing image file, an unknown camera id or a parameter
// count that does not fit the model throws Error naming it.
Sequence colmap_sequence(const std::string& scene_dir, const std::string& dataset, const ColmapSceneLayout& layout);

// Sparse depth prompts for a view from the model's 3D points: (u, v, z) of points projected inside it.
std::vector<Eigen::Vector3d> colmap_sparse_depth(const ColmapModel& model, const View& view);

}  // namespace isplat
