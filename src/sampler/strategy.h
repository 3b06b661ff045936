// Internal to the sampler: one small interface per placement strategy (sampler.mode), chosen by a factory.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "sampler/grid.h"

namespace isplat {
namespace sampling {

// What a strategy samples from: the depth map's grid, the options, and (when it takes a budget) the count and the
// detail weights (empty unless budget_mode = detail).
struct SampleRequest {
  const Grid& grid;
  const SamplerOptions& options;
  int64_t budget = 0;                // only when uses_budget()
  const std::vector<float>* weight;  // per-pixel detail weights, or empty
  uint64_t seed = 0;
  bool normals = false;  // fill Supports::normal
};

class SupportStrategy {
 public:
  virtual ~SupportStrategy() = default;
  // False when the strategy places a fixed number of supports (pixel mode: one per valid pixel).
  virtual bool uses_budget() const { return true; }
  virtual Supports sample(const SampleRequest& r) const = 0;
};

// area: area-weighted faces, with edge supports and hidden surface (area.cpp); pixel: one support per valid pixel
// (pixel.cpp); vertex_face: gradient-priority vertices plus area-weighted faces (vertex_face.cpp).
std::unique_ptr<SupportStrategy> make_support_strategy(const std::string& mode);

}  // namespace sampling
}  // namespace isplat
