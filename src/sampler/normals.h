// Internal to the sampler: surface normals at supports, from the accepted triangles around a pixel.
#pragma once
#include <cstdint>
#include <vector>

#include "core/error.h"
#include "sampler/grid.h"

namespace isplat {
namespace sampling {

// Twice the area vectors of the triangles of quad rows [first, first + rows), each computed at most once, when a
// pixel around it first asks; a band of rows, small enough to stay in cache.
class TriangleCrosses {
 public:
  explicit TriangleCrosses(const Grid& g) : g_(g), Wq_(g.W - 1) {}
  void reset(int64_t first_row, int64_t rows) {
    first_ = first_row, rows_ = rows;
    cross_.resize(static_cast<size_t>(rows * Wq_ * 6));
    state_.assign(static_cast<size_t>(rows * Wq_ * 2), kUnknown);
  }
  // Null where triangle_cross rejects the triangle.
  const double* at(int64_t i, int64_t j, int t) {
    ISPLAT_CHECK(i >= first_ && i < first_ + rows_ && j >= 0 && j < Wq_, "sampler: quad (", i, ", ", j,
                 ") outside the cached rows [", first_, ", ", first_ + rows_, ")");
    const int64_t q = ((i - first_) * Wq_ + j) * 2 + t;
    if (state_[q] == kUnknown) state_[q] = triangle_cross(g_, i, j, t, &cross_[3 * q]) ? kAccepted : kRejected;
    return state_[q] == kAccepted ? &cross_[3 * q] : nullptr;
  }

 private:
  enum : uint8_t { kUnknown, kAccepted, kRejected };
  const Grid& g_;
  int64_t Wq_, first_ = 0, rows_ = 0;
  std::vector<double> cross_;
  std::vector<uint8_t> state_;
};

// The normal of the depth surface at pixel (i, j): the area-weighted mean of the accepted triangles that have the
// pixel centre as a vertex, turned to face the camera. Where none is accepted (a lone pixel, a silhouette), the
// surface is taken to face the camera: -X / |X|.
void vertex_normal(const Grid& g, TriangleCrosses& tc, int64_t i, int64_t j, float* n);

// Every support takes the surface normal at the valid pixel nearest its position (fills s.normal).
void write_normals(const Grid& g, Supports& s);

}  // namespace sampling
}  // namespace isplat
