// Methods the evaluator scores: a trained checkpoint (RGB or LiDAR variant, or an ablation), and the
// baselines any reviewer asks for ("lift" and "identity").
#pragma once
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <string>

#include "core/gaussians.h"
#include "data/tuples.h"
#include "eval/eval_config.h"
#include "render/scale_align.h"

namespace isplat {

struct MethodOutput {
  torch::Tensor image;                                        // [3,H,W] sRGB in [0,1], the target view
  double infer_ms = 0;                                        // one image -> Gaussians (prior included)
  double render_ms = 0;                                       // Gaussians -> target view
  int64_t gaussians = 0;                                      // rendered (after pruning)
  int64_t decoded = 0;                                        // before pruning
  std::map<std::string, double> stage_ms;                     // prior, sampler, encoder, decoder, composer, prune
  std::map<std::string, int64_t> prune_counts;                // what pruning did (prune_counts()), when enabled
  double peak_mb = std::numeric_limits<double>::quiet_NaN();  // process peak memory during predict + render
  // CPU tensor memory predict + render needed beyond what was live before (core/tensor_memory; NaN when not counted)
  double work_mb = std::numeric_limits<double>::quiet_NaN();
  torch::Tensor alpha, depth, normal;  // the render's other outputs (RenderOutput), where the method renders
  torch::Tensor median_depth;          // RenderOutput::median_depth, when the method's RenderMaps ask for it
  // The Gaussians the method rendered (world frame) and whether their colours are linear, so the evaluator can render
  // them from other cameras (scoring.display_factors); scene.means undefined where the method has none (identity).
  Gaussians scene;
  bool linear_rgb = true;
  ScaleFit scale;               // what the evaluator's alignment applied (AlignScene); samples 0 when none
  bool aligned = false;         // an AlignScene was applied to `scene` before the render
  torch::Tensor densified;      // sparse prior: its depth [H,W] (the densified prompts), else undefined
  torch::Tensor prompt_pixels;  // ... and the prompts' pixels [P,2] (col, row) it was given or drew
};

// Changes a method's Gaussians (world frame) before it renders the target and returns what it did: the evaluator's
// scale alignment (scoring.align_scale). Empty = none.
using AlignScene = std::function<ScaleFit(Gaussians&)>;

// A render's colours [3,H,W] as the metrics compare them: clamped, and through the sRGB transfer when linear.
torch::Tensor rendered_srgb(const torch::Tensor& rgb, bool linear);

class Method {
 public:
  virtual ~Method() = default;
  // source: the source view (image, depth, valid, camera) at evaluation size; target: its camera.
  // prompts: sparse depth prompts [P,3] (u, v, z) for LiDAR-variant checkpoints, or undefined (then a
  // sparse prior draws them from the source depth).
  // align: applied to the Gaussians before the render, by the methods that render Gaussians.
  virtual MethodOutput predict(const ViewTensors& source, const Camera& target, uint64_t seed,
                               const torch::Tensor& prompts, const AlignScene& align = {}) = 0;
  virtual std::string describe() const = 0;
  // True when predict() needs the source view's depth (given `prompts`, or drawing them from the depth).
  virtual bool needs_source_depth(bool have_prompts) const { return false; }
};

// `render` and `maps` are how the method renders the target view (maps: what the scores read).
std::unique_ptr<Method> make_method(const MethodOptions& options, const RenderOptions& render, const RenderMaps& maps);

// Refuses (Error naming the method, the checkpoint and the pid) a checkpoint inside a run folder
// (<run>/checkpoints/<file>) that a trainer still holds locked: its scores would be of an unfinished run, and
// the fingerprint check would refuse to resume them once the run moved on.
void require_finished_run(const std::string& method, const std::string& checkpoint);

}  // namespace isplat
