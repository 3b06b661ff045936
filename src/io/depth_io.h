// Depth maps with explicit validity, and float depth through OpenEXR.
#pragma once
#include <opencv2/core.hpp>
#include <string>

namespace isplat {

// depth: CV_32FC1 planar metres, 0 where invalid. valid: CV_8UC1, 1 where depth is finite and > 0.
struct DepthMap {
  cv::Mat depth;
  cv::Mat valid;
  int64_t invalid_count = 0;
};

// Masks NaN, inf and <= 0 values; they come back as depth 0 with valid = 0. Never propagates NaN.
DepthMap sanitize_depth(const cv::Mat& raw);

// Reads one channel of an OpenEXR file as float32: `channel` if given, else Z, then Y, then R, else
// the only channel. Truncated or corrupt files throw Error naming the path.
cv::Mat read_exr_channel(const std::string& path, const std::string& channel = "");
DepthMap read_depth_exr(const std::string& path, const std::string& channel = "");

// Writes a CV_32FC1 map as channel "Z" (float32, or half when `half` is true), atomically.
void write_depth_exr(const std::string& path, const cv::Mat& depth, bool half = false);

}  // namespace isplat
