// Multi-view depth consistency for reader tests.
#include "support/consistency.h"

#include <algorithm>
#include <cmath>

namespace isplat::test {

Consistency depth_consistency(const LoadedFrame& source, const LoadedFrame& target, double tolerance, int step) {
  Consistency out;
  std::vector<double> errors;
  const Pose to_target = target.view.T_cw * invert_pose(source.view.T_cw);
  const auto& sd = source.depth;
  for (int i = 0; i < sd.depth.rows; i += step)
    for (int j = 0; j < sd.depth.cols; j += step) {
      if (!sd.valid.at<uint8_t>(i, j)) continue;
      const Eigen::Vector3d X = source.view.intr.backproject(j + 0.5, i + 0.5, sd.depth.at<float>(i, j));
      const Eigen::Vector3d Xt = transform_point(to_target, X);
      if (Xt.z() <= 0) continue;
      // Bilinear interpolation of inverse depth at the projected point (exact on planes); skip depth edges.
      const Eigen::Vector2d uv = target.view.intr.project(Xt);
      const double x = uv.x() - 0.5, y = uv.y() - 0.5;
      const int u = static_cast<int>(std::floor(x)), v = static_cast<int>(std::floor(y));
      if (u < 0 || v < 0 || u + 1 >= target.depth.depth.cols || v + 1 >= target.depth.depth.rows) continue;
      double inv[4];
      bool ok = true;
      for (int k = 0; k < 4; ++k) {
        const int uu = u + (k & 1), vv = v + (k >> 1);
        ok = ok && target.depth.valid.at<uint8_t>(vv, uu);
        inv[k] = ok ? 1.0 / target.depth.depth.at<float>(vv, uu) : 0.0;
      }
      if (!ok) continue;
      const double lo = *std::min_element(inv, inv + 4), hi = *std::max_element(inv, inv + 4);
      if (hi > 1.1 * lo) continue;  // a depth edge: interpolation is meaningless there
      const double fx = x - u, fy = y - v;
      const double inv_z = (inv[0] * (1 - fx) + inv[1] * fx) * (1 - fy) + (inv[2] * (1 - fx) + inv[3] * fx) * fy;
      errors.push_back(std::fabs(1.0 / inv_z - Xt.z()) / Xt.z());
    }
  out.checked = static_cast<int64_t>(errors.size());
  if (errors.empty()) return out;
  out.agree = std::count_if(errors.begin(), errors.end(), [&](double e) { return e < tolerance; }) /
              static_cast<double>(errors.size());
  std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
  out.median_rel = errors[errors.size() / 2];
  return out;
}

}  // namespace isplat::test
