// One photo -> Gaussians with a loaded checkpoint: the steps `infinisplat predict` and the Python Predictor share.
#pragma once
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "core/gaussians.h"
#include "geometry/camera.h"
#include "model/infinisplat.h"
#include "render/merge.h"
#include "render/prune.h"

namespace isplat {

// The view floor's default: the smallest floor (in steps of 0.05 px) with at most 0.1% gaps at 4x on every
// development frame, for both seeds of the recipe (lab/2026-12-06-display-holes).
constexpr double kViewFloorPx = 0.45;

// How messages name the options: as the CLI's flags ("--prune-views") or as Python's keywords ("prune_views").
enum class OptionNames { Flags, Keywords };

// The photo's intrinsics: fx, else the EXIF 35 mm focal length, else hfov, else the checkpoint's prior.hfov_deg.
struct PhotoIntrinsicsOptions {
  std::optional<double> fx, fy, cx, cy;  // photo pixels; fy (default fx) and the principal point (default the
                                         // centre) refine fx and need it
  std::optional<double> hfov;            // horizontal field of view in degrees, [1, 179]
};

struct PhotoPredictOptions {
  PhotoIntrinsicsOptions intrinsics;
  int64_t width = 0, height = 0;     // the working size, multiples of 16, both or neither (0: the training
                                     // resolution's area at the photo's aspect, in multiples of 16)
  bool photo_size = false;           // the photo's own size in multiples of 16 instead (before width and height)
  uint64_t seed = 0;                 // the sampler's
  double view_floor = kViewFloorPx;  // the composer's scale floor raised to this many working-size pixels, [0, 4]
  double prune_opacity = 0.02;       // drop Gaussians below this opacity
  double prune_contribution = 0;     // drop Gaussians whose largest weight in the views stays below this (0 = off)
  int64_t prune_views = 4;           // nearby views for prune_contribution: 0, 2, 4 or 6
  MergeOptions merge;                // off unless merge.cell_px > 0 (the caller checks its bounds)
  bool keep_outside = false;         // keep Gaussians whose centre leaves the source view
  OptionNames names = OptionNames::Flags;
};

// The option's name in messages: "--view-floor" or "view_floor" for the key "view_floor".
std::string option_name(OptionNames names, const std::string& key);

// The checks that need no photo (pairs given together, multiples of 16, bounds), naming the options as
// options.names says. predict() makes them too; a caller can make them before loading anything.
void check_photo_options(const PhotoPredictOptions& options);

// One photo and what comes with it.
struct PhotoInput {
  cv::Mat photo;          // float RGB in [0, 1] (CV_32FC3), any size
  std::string label;      // names the photo in messages: its path, a video frame
  std::string exif_from;  // the file whose EXIF may give the focal length ("": none)
  cv::Mat depth;  // optional metric planar depth (CV_32FC1, metres, 0 = none) of the photo's view, any size of its
                  // aspect
  std::string depth_label;                     // names the depth in messages after its option (the CLI: the path)
  std::vector<std::array<double, 3>> prompts;  // optional sparse depth prompts: u, v in photo pixels, z in metres
};

// The photo's camera and working size, and the model's input.
struct PhotoFrame {
  Intrinsics intrinsics;          // the photo's, at its own size
  std::string intrinsics_source;  // "given", "EXIF (...)" or "estimated from a ... degree field of view"
  View view;                      // the working size's camera, at the identity pose
  int width = 0, height = 0;      // the working size
  PriorInput input;               // the resized photo, K, seed, depth and prompts at the working size
};

struct PhotoPrediction {
  PhotoFrame frame;
  Prediction prediction;  // the pipeline's (supports, timings; its Gaussians as decoded)
  Gaussians gaussians;    // what is left after the hook, dropping and pruning
  int64_t decoded = 0;    // Gaussians before dropping and pruning
  int64_t outside = 0;    // dropped because their centre left the source view
  PruneResult pruned;     // pruning's counts
  double prune_ms = 0;
  double scale_floor_px = 0;  // the composer's floor the Gaussians were made with
};

// What a caller adds between the steps (the CLI's --max-gaussians and --align-points).
struct PhotoHooks {
  // May change the prior's output before the model sees it (Pipeline::run's after_prior).
  std::function<void(PriorOutput&, const PhotoFrame&)> after_prior;
  // May change the decoded Gaussians before dropping and pruning.
  std::function<void(Gaussians&, const PhotoFrame&)> after_decode;
};

// A checkpoint loaded once for predicting photos.
class PhotoPredictor {
 public:
  // `overrides`: model config keys to change ("prior.type=dataset"), as the CLI's --set.
  PhotoPredictor(const std::string& checkpoint, const std::vector<std::string>& overrides = {});
  ~PhotoPredictor();

  // The working size of a photo: the training resolution's area at its aspect in multiples of 16, the photo's own
  // size with options.photo_size, or options.width x options.height.
  std::pair<int, int> working_size(int photo_width, int photo_height, const PhotoPredictOptions& options) const;

  // One photo -> Gaussians in its camera's frame: intrinsics, working size, the prior's input (the photo, depth and
  // prompts resized), the composer's floor raised to the view floor, the pipeline, then dropping the centres that
  // leave the source view and pruning.
  PhotoPrediction predict(const PhotoInput& input, const PhotoPredictOptions& options, const PhotoHooks& hooks = {});

  Pipeline& pipeline() { return *pipeline_; }
  double trained_floor_px() const { return trained_floor_px_; }

 private:
  std::unique_ptr<Pipeline> pipeline_;
  int64_t train_width_ = 256, train_height_ = 192;  // the stored training size (the default without one)
  double trained_floor_px_ = 0;
};

}  // namespace isplat
