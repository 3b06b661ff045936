// sampler.mode = area: area-weighted faces, optionally with edge supports, their band and shift, and hidden surface.
#include <numeric>

#include "sampler/edges.h"
#include "sampler/faces.h"
#include "sampler/normals.h"
#include "sampler/strategy.h"

namespace isplat {
namespace sampling {

namespace {

class AreaStrategy final : public SupportStrategy {
 public:
  Supports sample(const SampleRequest& r) const override {
    const Grid& g = r.grid;
    const SamplerOptions& options = r.options;
    const uint64_t seed = r.seed;
    const bool normals = r.normals;
    const int64_t n = r.budget;
    const std::vector<float>& weight = *r.weight;
    Supports s = allocate(n);
    const Output o = pointers(s);
    std::vector<float> area = triangle_areas(g);
    int64_t ne = 0, nb = 0;
    double total = 0;
    for (float a : area) total += a;  // the whole surface, before a band takes triangles from the faces
    Behind behind;
    if (options.edge_supports) {
      const std::vector<int64_t> edges = edge_band_pixels(g, area, options.edge_band, n / 2);
      ne = std::min<int64_t>(static_cast<int64_t>(edges.size()), n / 2);  // faces keep at least half
      const std::vector<int64_t> chosen = spread(edges, ne);
      write_pixel_supports(g, o, chosen, ne);
      shift_edge_supports(g, o, chosen, options.edge_shift);
      if (options.edge_behind > 0) {  // at most half the budget with the edge supports, thinned evenly
        behind = behind_places(g, chosen, options.edge_behind);
        const int64_t places = static_cast<int64_t>(behind.depth.size());
        nb = std::min<int64_t>(places, n / 2 - ne);
        if (nb < places) {
          std::vector<int64_t> all(static_cast<size_t>(places));
          std::iota(all.begin(), all.end(), int64_t(0));
          behind = select_places(behind, spread(all, nb));
        }
      }
    }
    const double face_total =
        sample_faces(g, std::move(area), n - ne - nb, seed, o, ne, weight.empty() ? nullptr : weight.data(),
                     options.image_share, options.pixel_floor);
    if (ne > 0) rescale_areas(s, options.edge_band > 0 ? total : face_total, n - nb);
    write_behind(g, o, behind, nb, n - nb);
    s.behind = nb;
    if (normals) {
      write_normals(g, s);
      behind_normals(g, s, behind, nb, n - nb);
    }
    return s;
  }
};

}  // namespace

std::unique_ptr<SupportStrategy> make_area_strategy() {
  return std::make_unique<AreaStrategy>();
}

}  // namespace sampling
}  // namespace isplat
