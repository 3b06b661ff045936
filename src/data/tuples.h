// Context/target tuples for training: 1 context view + T target views from one trajectory, resized to
// the training resolution with intrinsics adjusted, deterministic from (seed, index).
#pragma once
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include <torch/types.h>

#include "data/augment.h"
#include "data/sequence.h"
#include "geometry/camera_torch.h"

namespace isplat {

class ConfigVisitor;

struct TupleOptions {
  int64_t targets = 3;
  int64_t width = 256, height = 192;
  int64_t window = 10;           // targets come from frames within +-window of the context
  double min_overlap = 0.3;      // minimum frustum overlap of the context with each target
  double min_valid_depth = 0.5;  // contexts with less valid depth are resampled
  int64_t max_attempts = 32;
  AugmentOptions augment;  // training tuples only: the trainer turns it off for validation
  void visit(ConfigVisitor& v);
};

// One view at training resolution.
struct ViewTensors {
  torch::Tensor image;  // [3,H,W] sRGB in [0,1]
  torch::Tensor depth;  // [H,W] planar metres, 0 where invalid
  torch::Tensor valid;  // [H,W] float 0/1
  Camera camera;        // K [3,3], T_cw [4,4] (float32)
  std::string name;
  torch::Tensor true_depth = {};  // [H,W] the depth before perturb_source changed it (evaluation), else undefined
};

struct TupleSample {
  ViewTensors context;
  std::vector<ViewTensors> targets;
  std::vector<double> baselines;  // metres, context -> each target
  std::vector<double> overlaps;   // measured before augmentation (a zoom crops each view on its own)
};

// A collated batch of B tuples (all with T targets).
struct Batch {
  torch::Tensor context_image, context_depth, context_valid;  // [B,3,H,W], [B,H,W], [B,H,W]
  torch::Tensor context_K, context_T;                         // [B,3,3], [B,4,4]
  torch::Tensor target_image, target_depth, target_valid;     // [B,T,3,H,W], [B,T,H,W], [B,T,H,W]
  torch::Tensor target_K, target_T;                           // [B,T,3,3], [B,T,4,4]
  std::vector<std::string> names;                             // context frame names
  int64_t size() const { return context_image.size(0); }
  int64_t targets() const { return target_image.size(1); }
};

Batch collate(const std::vector<TupleSample>& samples);
ViewTensors make_view_tensors(const LoadedFrame& frame, const std::string& name, int64_t width, int64_t height);

class TupleSampler {
 public:
  TupleSampler(std::vector<Sequence> sequences, TupleOptions options, uint64_t seed);

  // The tuple for `index` (same seed and index -> same tuple). Frames that fail to load are skipped with
  // a counted warning and another draw is made; throws Error only when max_attempts draws all fail.
  TupleSample sample(int64_t index) const;

  int64_t frame_count() const { return total_frames_; }
  const std::vector<Sequence>& sequences() const { return sequences_; }
  std::map<std::string, int64_t> skip_counts() const;

 private:
  std::vector<Sequence> sequences_;
  std::vector<int64_t> cumulative_;  // frames before sequence i
  int64_t total_frames_ = 0;
  TupleOptions options_;
  uint64_t seed_;
  mutable std::mutex skip_mutex_;
  mutable std::map<std::string, int64_t> skips_;
  void count_skip(const std::string& reason) const;
};

// SplitMix64, used to derive independent deterministic streams from (seed, index).
uint64_t mix_seed(uint64_t seed, uint64_t index);

}  // namespace isplat
