// Internal to the sampler: area faces, supports drawn on the accepted triangles by stratified allocation over
// their (weighted) 3D area, placed by a low-discrepancy sequence inside each triangle.
#pragma once
#include <cstdint>
#include <vector>

#include "sampler/grid.h"

namespace isplat {
namespace sampling {

// Area-weighted stratified sampling of n supports into o starting at `first`. Returns the total area.
// `area`: triangle_areas(g). `weight` (per pixel, or null): triangles are drawn in proportion to area × the
// weight of their quad's first vertex, and each support then stands for a share of area inversely
// proportional to that weight. `image_share` and `pixel_floor` as in SamplerOptions.
double sample_faces(const Grid& g, std::vector<float> area, int64_t n, uint64_t seed, const Output& o, int64_t first,
                    const float* weight = nullptr, double image_share = 0.0, double pixel_floor = 0.0);

}  // namespace sampling
}  // namespace isplat
