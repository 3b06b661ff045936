// Internal to the sampler: edges and hidden surface. Edge supports on the pixels where the faces stop (depth edges,
// holes, the border), the band around them, the near side's shift off the silhouette, and supports that continue the
// farther surface under a silhouette (edge_behind).
#pragma once
#include <cstdint>
#include <vector>

#include "sampler/grid.h"

namespace isplat {
namespace sampling {

// The edge pixels widened by `band` pixels over valid pixels, row-major: the near side of depth edges, over its own
// surface (far sides, holes and the border keep faces up to their edge pixels). The triangles whose three vertices all
// lie in the band get area 0, so faces leave the band to its pixel supports. A band of more than `max_pixels` would
// leave band pixels with neither kind of support, so the edge pixels alone are returned then. `area`:
// triangle_areas(g).
std::vector<int64_t> edge_band_pixels(const Grid& g, std::vector<float>& area, int64_t band, int64_t max_pixels);

// Supports 0..pixels.size()-1, at those pixels' centres, on the near side of a depth edge move `shift` pixels away
// from the farther neighbours, into their own surface, keeping their depth, colour and footprint.
void shift_edge_supports(const Grid& g, const Output& o, const std::vector<int64_t>& pixels, double shift);

// Where the farther surface continues under a silhouette: for each of `pixels` on the near side of a depth edge
// (near_side; the others are skipped), up to `layers` places one pixel apart, from its centre
// going inwards, away from the farther neighbours. Each farther neighbour's surface is extrapolated as a
// plane to the place (or kept at its own depth where the plane would come as near as the pixel over the place); the
// place takes their mean depth and their mean colour. Layering stops where the place would not be hidden: beyond the
// image, over an invalid pixel or one not nearer than it, or (after the first) where the farther neighbours surround
// the pixel evenly, as on a line one pixel wide.
struct Behind {
  std::vector<double> u, v;
  std::vector<float> depth, color;  // colour: 3 per place
  std::vector<int64_t> from;        // the farther neighbour whose surface it continues (its normal is used)
};

Behind behind_places(const Grid& g, const std::vector<int64_t>& pixels, int64_t layers);

// The places of `b` at `indices`, in that order.
Behind select_places(const Behind& b, const std::vector<int64_t>& indices);

// Writes places [0, count) of `b` as supports first.. with a pixel's footprint at their depth (they stand for
// hidden surface, so they stay out of the visible surface's area total).
void write_behind(const Grid& g, const Output& o, const Behind& b, int64_t count, int64_t first);

// Behind supports first..first+count-1 take the normal of the farther pixel they continue, not the near surface's
// at their place.
void behind_normals(const Grid& g, Supports& s, const Behind& b, int64_t count, int64_t first);

}  // namespace sampling
}  // namespace isplat
