// A camera sequence from any dataset (Hypersim trajectory, COLMAP model, nerfstudio capture) and the
// loading of one frame into an image, a planar depth map with validity, and its view.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "geometry/camera.h"
#include "geometry/convert.h"
#include "io/depth_io.h"

namespace isplat {

enum class DepthSource {
  None,              // no depth file
  HypersimRayHdf5,   // Hypersim depth_meters: distance along the ray, float16 HDF5 (converted to planar z)
  PlanarExr,         // planar z in metres, OpenEXR
  Png16Millimetres,  // planar z in millimetres, 16-bit PNG (0 = invalid)
  RawFloat32,        // ETH3D: headerless little-endian float32, planar z in metres, row-major W x H
};

enum class ColorSource {
  Image,         // PNG/JPG through OpenCV
  HypersimHdf5,  // linear HDR float16 HDF5, tone-mapped with Hypersim's operator
};

struct FrameRecord {
  std::string name;  // unique within the dataset, e.g. "ai_001_001/cam_00/0007"
  std::string image_path;
  ColorSource color = ColorSource::Image;
  std::string depth_path;  // empty when there is none
  DepthSource depth = DepthSource::None;
  View view;                       // intrinsics at the file's native resolution; T_cw in metres
  std::vector<double> distortion;  // OpenCV k1 k2 p1 p2 [k3..k6]; non-empty -> undistorted on load
  bool rescale_to_image = false;   // nerfstudio: scale K when the image file is a resized copy
};

struct Sequence {
  std::string dataset;  // e.g. "hypersim", "synthetic-courtyard"
  std::string scene;    // e.g. "ai_001_001"
  std::string name;     // e.g. "cam_00"
  std::vector<FrameRecord> frames;
  std::shared_ptr<const HypersimCamera> hypersim;  // set for Hypersim sequences (ray -> planar depth)
  std::string id() const { return scene + "/" + name; }
};

struct LoadedFrame {
  cv::Mat image;   // CV_32FC3 sRGB in [0, 1]
  DepthMap depth;  // empty Mats when the frame has no depth
  View view;
  bool has_depth() const { return !depth.depth.empty(); }
};

// Loads one frame. Missing or corrupt files throw Error naming the file. Depth comes back planar, in
// metres, with NaN/inf/<=0 masked. Image and depth must have the intrinsics' size.
LoadedFrame load_frame(const Sequence& sequence, size_t index, bool with_depth = true);

// Hypersim's tone map for HDR colour: scale so the 90th percentile of luminance maps to 0.8 after
// gamma 2.2, then gamma-encode and clip. `valid` (optional, CV_8U) selects the pixels that count.
cv::Mat hypersim_tonemap(const cv::Mat& linear_rgb, const cv::Mat& valid = cv::Mat());
double hypersim_exposure(const cv::Mat& linear_rgb, const cv::Mat& valid = cv::Mat());  // the scale above
cv::Mat apply_exposure_gamma(const cv::Mat& linear_rgb, double scale);                  // clip(max(0, s*x)^(1/2.2))

// Fraction of the source's valid depth samples (on a coarse grid) that land inside `target` in front of
// it: the frustum overlap of DESIGN §5. Returns 0 when the source has no valid depth.
double frustum_overlap(const View& source, const DepthMap& source_depth, const View& target, int grid = 32);

// Distance between camera centres in metres.
double baseline(const View& a, const View& b);

}  // namespace isplat
