// sampler.mode = vertex_face (the release's): supports on the valid pixels with the strongest image gradients, the
// rest area-weighted on the faces.
#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "sampler/faces.h"
#include "sampler/normals.h"
#include "sampler/strategy.h"

namespace isplat {
namespace sampling {

namespace {

class VertexFaceStrategy final : public SupportStrategy {
 public:
  Supports sample(const SampleRequest& r) const override {
    const Grid& g = r.grid;
    const SamplerOptions& options = r.options;
    const uint64_t seed = r.seed;
    const bool normals = r.normals;
    const int64_t n = r.budget;
    // Vertices: valid pixel centres with the strongest image gradients (the release's priority).
    std::vector<float> grad(static_cast<size_t>(g.H * g.W), -1.0f);
    at::parallel_for(0, g.H, 16, [&](int64_t b, int64_t e) {
      for (int64_t i = b; i < e; ++i)
        for (int64_t j = 0; j < g.W; ++j) {
          if (g.valid[i * g.W + j] == 0.0f) continue;
          float s2 = 0;
          for (int c = 0; c < 3; ++c) {
            const float* m = g.image + c * g.H * g.W;
            const float gx = m[i * g.W + std::min(j + 1, g.W - 1)] - m[i * g.W + std::max<int64_t>(j - 1, 0)];
            const float gy = m[std::min(i + 1, g.H - 1) * g.W + j] - m[std::max<int64_t>(i - 1, 0) * g.W + j];
            s2 += gx * gx + gy * gy;
          }
          grad[i * g.W + j] = s2;
        }
    });
    std::vector<int64_t> priority;
    priority.reserve(grad.size());
    for (int64_t p = 0; p < g.H * g.W; ++p)
      if (grad[p] >= 0) priority.push_back(p);
    ISPLAT_CHECK(!priority.empty(), "sampler: the depth map has no valid pixel (all depth is invalid: NaN/inf/<=0)");
    const int64_t nv = std::min<int64_t>(static_cast<int64_t>(std::llround(options.vertex_fraction * n)),
                                         static_cast<int64_t>(priority.size()));
    // The nv strongest gradients (ties by pixel index); nth_element is deterministic for equal input.
    auto stronger = [&](int64_t a, int64_t b) { return grad[a] > grad[b] || (grad[a] == grad[b] && a < b); };
    std::nth_element(priority.begin(), priority.begin() + nv, priority.end(), stronger);
    Supports s = allocate(n);
    const Output o = pointers(s);
    write_pixel_supports(g, o, priority, nv);
    rescale_areas(s, sample_faces(g, triangle_areas(g), n - nv, seed, o, nv));
    if (normals) write_normals(g, s);
    return s;
  }
};

}  // namespace

std::unique_ptr<SupportStrategy> make_vertex_face_strategy() {
  return std::make_unique<VertexFaceStrategy>();
}

}  // namespace sampling
}  // namespace isplat
