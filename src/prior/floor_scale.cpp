// The metric scale from the camera's height: RANSAC finds the floor in the lower image (prior.camera_height_m).
#include <torch/torch.h>

#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Eigenvalues>

#include "core/error.h"
#include "geometry/camera_torch.h"
#include "prior/depth_prior.h"

namespace isplat {

double floor_height_scale(const torch::Tensor& depth, const torch::Tensor& valid, const torch::Tensor& K,
                          double height_m) {
  ISPLAT_CHECK(height_m > 0, "floor_height_scale: the camera height must be positive, got ", height_m);
  ISPLAT_CHECK(depth.dim() == 2 && K.dim() == 2 && K.size(0) == 3 && K.size(1) == 3,
               "floor_height_scale: depth must be [H,W] and K [3,3], got ", depth.sizes(), " and ", K.sizes());
  auto d = depth.to(torch::kFloat32).contiguous();
  auto ok = usable_depth(d, valid.defined() ? valid : (d > 0)).contiguous();
  auto k = K.to(torch::kFloat64).contiguous();
  const double* kp = k.data_ptr<double>();
  const double fx = kp[0], fy = kp[4], cx = kp[2], cy = kp[5];
  const int64_t H = d.size(0), W = d.size(1), top = H / 2;
  // About 4000 samples from the lower half, where the ground of a photo taken standing shows.
  const int64_t stride =
      std::max<int64_t>(1, static_cast<int64_t>(std::sqrt(static_cast<double>((H - top) * W) / 4000.0)));
  const float* dp = d.data_ptr<float>();
  const bool* okp = ok.data_ptr<bool>();
  std::vector<Eigen::Vector3d> pts;
  for (int64_t i = top; i < H; i += stride)
    for (int64_t j = 0; j < W; j += stride)
      if (okp[i * W + j]) {
        const double z = dp[i * W + j];
        pts.emplace_back((j + 0.5 - cx) / fx * z, (i + 0.5 - cy) / fy * z, z);
      }
  const auto n_pts = static_cast<int64_t>(pts.size());
  constexpr int64_t kMinPoints = 30;
  if (n_pts < kMinPoints) return 0.0;
  // Up is -y in the OpenCV camera frame; a floor's normal points up and the floor lies below (h > 0).
  const double min_up = std::cos(40.0 * M_PI / 180.0), tol = 0.02;  // tol: distance as a share of depth
  std::vector<char> active(static_cast<size_t>(n_pts), 1);          // points no earlier plane claimed
  auto inliers = [&](const Eigen::Vector3d& n, double h, double share, std::vector<int64_t>* out) {
    int64_t count = 0;
    for (int64_t p = 0; p < n_pts; ++p)
      if (active[p] && std::fabs(n.dot(pts[p]) + h) <= share * pts[p].z()) {
        ++count;
        if (out) out->push_back(p);
      }
    return count;
  };
  struct Plane {
    Eigen::Vector3d n;
    double h = 0;
    int64_t support = 0;
  };
  std::mt19937_64 rng(0x5EEDF100Full);
  // RANSAC over the active points, then weighted least-squares refits on the inliers: weights 1/z^2 make
  // residuals relative, as the depth's errors are, so far points near a wall's crease do not tilt the plane;
  // the second refit uses half the tolerance.
  auto fit_plane = [&]() {
    std::vector<int64_t> pool;
    for (int64_t p = 0; p < n_pts; ++p)
      if (active[p]) pool.push_back(p);
    Plane best;
    if (static_cast<int64_t>(pool.size()) < kMinPoints) return best;
    for (int iter = 0; iter < 256; ++iter) {
      const auto& a = pts[pool[rng() % pool.size()]];
      const auto& b = pts[pool[rng() % pool.size()]];
      const auto& c = pts[pool[rng() % pool.size()]];
      Eigen::Vector3d n = (b - a).cross(c - a);
      if (n.norm() < 1e-12) continue;
      n.normalize();
      if (n.y() > 0) n = -n;
      const double h = -n.dot(a);
      if (-n.y() < min_up || h <= 0) continue;
      const int64_t count = inliers(n, h, tol, nullptr);
      if (count > best.support) best = {n, h, count};
    }
    if (best.support == 0) return best;
    for (int round = 0; round < 2; ++round) {
      std::vector<int64_t> in;
      inliers(best.n, best.h, tol / (1 + round), &in);
      double wsum = 0;
      Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
      for (int64_t p : in) {
        const double w = 1.0 / (pts[p].z() * pts[p].z());
        centroid += w * pts[p], wsum += w;
      }
      centroid /= wsum;
      Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
      for (int64_t p : in) cov += (pts[p] - centroid) * (pts[p] - centroid).transpose() / (pts[p].z() * pts[p].z());
      Eigen::Vector3d refit = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvectors().col(0);
      if (refit.y() > 0) refit = -refit;
      const double refit_h = -refit.dot(centroid);
      if (-refit.y() < min_up || refit_h <= 0) break;  // degenerate refit: keep the plane so far
      best.n = refit, best.h = refit_h;
    }
    return best;
  };
  const int64_t min_support = std::max<int64_t>(kMinPoints, n_pts / 10);
  auto plausible = [&](const Plane& p) {
    const double scale = height_m / p.h;
    return p.support >= min_support && scale > 0.02 && scale < 50.0;  // beyond: not a floor at any scale
  };
  const Plane first = fit_plane();
  if (!plausible(first)) return 0.0;
  return height_m / first.h;
}

}  // namespace isplat
