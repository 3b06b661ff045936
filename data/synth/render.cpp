// Ray-traced frames: per-pixel rays from the camera's linear map, shading with shadows, supersampling.
#include "data/synth/render.h"

#include <ATen/Parallel.h>

#include <cmath>
#include <limits>

namespace isplat::synth {

RayCamera pinhole_ray_camera(const CameraPose& pose, const Intrinsics& intr) {
  RayCamera c;
  c.center = pose.center;
  c.A = pose.R_wc * intr.K().inverse();
  c.forward = pose.R_wc.col(2);
  c.width = intr.width;
  c.height = intr.height;
  return c;
}

RayCamera hypersim_ray_camera(const CameraPose& pose, const Eigen::Matrix3d& M, int width, int height) {
  Mat3 S_inv;  // continuous pixel -> (u, v, 1)
  S_inv << 2.0 / width, 0, -1, 0, -2.0 / height, 1, 0, 0, 1;
  const Mat3 R_wc_gl = pose.R_wc * Eigen::Vector3d(1, -1, -1).asDiagonal();
  RayCamera c;
  c.center = pose.center;
  c.A = R_wc_gl * M * S_inv;
  c.forward = pose.R_wc.col(2);
  c.width = width;
  c.height = height;
  return c;
}

RenderedFrame render_frame(const Scene& scene, const RayCamera& cam, int supersample) {
  const int W = cam.width, H = cam.height, ss = std::max(1, supersample);
  RenderedFrame out;
  out.radiance = cv::Mat(H, W, CV_32FC3);
  out.distance = cv::Mat(H, W, CV_32FC1);
  out.planar = cv::Mat(H, W, CV_32FC1);
  out.hit = cv::Mat(H, W, CV_8UC1);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  at::parallel_for(0, H, 1, [&](int64_t begin, int64_t end) {
    for (int64_t i = begin; i < end; ++i) {
      cv::Vec3f* rad = out.radiance.ptr<cv::Vec3f>(static_cast<int>(i));
      float* dist = out.distance.ptr<float>(static_cast<int>(i));
      float* planar = out.planar.ptr<float>(static_cast<int>(i));
      uint8_t* hit_row = out.hit.ptr<uint8_t>(static_cast<int>(i));
      for (int j = 0; j < W; ++j) {
        Vec3 sum = Vec3::Zero();
        for (int a = 0; a < ss; ++a)
          for (int b = 0; b < ss; ++b) {
            const double x = j + (b + 0.5) / ss, y = i + (a + 0.5) / ss;
            const Vec3 d = (cam.A * Vec3(x, y, 1.0)).normalized();
            Hit h;
            sum += scene.intersect(cam.center, d, 1e6, h) ? scene.shade(d, h) : scene.sky(d);
          }
        const Vec3 c = sum / (ss * ss);
        rad[j] = cv::Vec3f(static_cast<float>(c.x()), static_cast<float>(c.y()), static_cast<float>(c.z()));
        const Vec3 d = (cam.A * Vec3(j + 0.5, i + 0.5, 1.0)).normalized();
        Hit h;
        if (scene.intersect(cam.center, d, 1e6, h)) {
          dist[j] = static_cast<float>(h.t);
          planar[j] = static_cast<float>(h.t * d.dot(cam.forward));
          hit_row[j] = 1;
        } else {
          dist[j] = planar[j] = nan;
          hit_row[j] = 0;
        }
      }
    }
  });
  return out;
}

}  // namespace isplat::synth
