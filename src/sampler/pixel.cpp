// sampler.mode = pixel (the default since config_version 3; the paper's ablation without edge_behind): one support per
// valid pixel centre, with the edge shift and hidden surface on top.
#include "core/error.h"
#include "sampler/edges.h"
#include "sampler/normals.h"
#include "sampler/strategy.h"

namespace isplat {
namespace sampling {

namespace {

class PixelStrategy final : public SupportStrategy {
 public:
  bool uses_budget() const override { return false; }
  Supports sample(const SampleRequest& r) const override {
    const Grid& g = r.grid;
    const SamplerOptions& options = r.options;
    const bool normals = r.normals;
    std::vector<int64_t> idx;
    for (int64_t p = 0; p < g.H * g.W; ++p)
      if (g.valid[p] != 0.0f) idx.push_back(p);
    ISPLAT_CHECK(!idx.empty(), "sampler: the depth map has no valid pixel (all depth is invalid: NaN/inf/<=0)");
    Behind behind;  // pixel mode has no budget: hidden supports come on top of one support per pixel
    if (options.edge_behind > 0) behind = behind_places(g, idx, options.edge_behind);
    const int64_t nv = static_cast<int64_t>(idx.size()), nb = static_cast<int64_t>(behind.depth.size());
    ISPLAT_CHECK(nv + nb <= kMaxSupports, "sampler: pixel mode places one support per valid pixel: ", nv + nb, " at ",
                 g.W, "x", g.H, ", above the limit of ", kMaxSupports,
                 " supports; use a smaller working size, or sampler.mode = area with a budget (predict: "
                 "--max-gaussians)");
    Supports s = allocate(nv + nb);
    const Output o = pointers(s);
    write_pixel_supports(g, o, idx, nv);
    shift_edge_supports(g, o, idx, options.edge_shift);
    write_behind(g, o, behind, nb, nv);
    s.behind = nb;
    if (normals) {
      write_normals(g, s);
      behind_normals(g, s, behind, nb, nv);
    }
    return s;
  }
};

}  // namespace

std::unique_ptr<SupportStrategy> make_pixel_strategy() {
  return std::make_unique<PixelStrategy>();
}

}  // namespace sampling
}  // namespace isplat
