// The embedded default dataset: procedural training scenes in the exact Hypersim layout, and
// evaluation scenes of other styles in COLMAP (text + binary, EXR depth) and nerfstudio layouts.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "core/runtime.h"

namespace isplat {

class ConfigVisitor;

struct GenerateOptions {
  std::string out = "out/data";
  int64_t seed = 7;
  int64_t train_scenes = 6, val_scenes = 1, test_scenes = 1;
  int64_t cameras_per_scene = 1;
  int64_t frames = 36;
  double room_max_step = 0.8;  // largest camera step in rooms (m): windows of 10 views reach past 2 m
  std::vector<std::string> train_styles = {"room"};  // Hypersim-layout scene styles, cycled over the scenes
  std::vector<double> hfov_deg = {60.0, 60.0};       // horizontal field of view range of Hypersim-layout cameras
  int64_t width = 384, height = 288;
  int64_t supersample = 2;
  int64_t tilt_shift_every = 3;
  bool hdf5_color = true;
  std::vector<std::string> eval_datasets = {"courtyard_colmap", "atrium_nerfstudio"};
  int64_t eval_scenes = 2;
  int64_t eval_frames = 40;
  int64_t eval_width = 384, eval_height = 256;
  void visit(ConfigVisitor& v);
};

struct GenerateConfig {
  RuntimeOptions runtime;
  GenerateOptions generate;
  void visit(ConfigVisitor& v);
};

// Writes everything under options.out: hypersim/ (root with the metadata CSVs) and eval/<dataset>/<scene>/.
// Prints a progress bar with ETA; deterministic in options.seed.
void generate_datasets(const GenerateOptions& options);

// Folder names used by the generated layout (for configs and tests).
std::string generated_hypersim_root(const std::string& out);
std::string generated_eval_root(const std::string& out, const std::string& dataset);

}  // namespace isplat
