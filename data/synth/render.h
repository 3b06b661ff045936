// Renders one view of a procedural scene: linear radiance, distance along each ray, and planar depth.
#pragma once
#include <opencv2/core.hpp>

#include "data/synth/builder.h"
#include "geometry/camera.h"

namespace isplat::synth {

// A camera as a linear map from continuous pixel (x, y) to a world-space ray direction: d = A·(x, y, 1).
struct RayCamera {
  Vec3 center;
  Mat3 A;
  Vec3 forward;  // unit axis planar depth is measured along
  int width = 0, height = 0;
};

RayCamera pinhole_ray_camera(const CameraPose& pose, const Intrinsics& intr);
// Hypersim's model: OpenGL camera axes and M_cam_from_uv over u = 2x/W - 1, v = 1 - 2y/H.
RayCamera hypersim_ray_camera(const CameraPose& pose, const Eigen::Matrix3d& M_cam_from_uv, int width, int height);

struct RenderedFrame {
  cv::Mat radiance;  // CV_32FC3 linear RGB
  cv::Mat distance;  // CV_32FC1 metres along the pixel-centre ray, NaN where nothing is hit
  cv::Mat planar;    // CV_32FC1 metres along `forward`, NaN where nothing is hit
  cv::Mat hit;       // CV_8UC1 1 where the pixel-centre ray hit geometry
};

// `supersample` x `supersample` regular samples per pixel for colour; depth from the pixel centre.
// Rows are rendered in parallel; the result is deterministic.
RenderedFrame render_frame(const Scene& scene, const RayCamera& camera, int supersample = 2);

}  // namespace isplat::synth
