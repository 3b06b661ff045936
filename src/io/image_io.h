// PNG/JPG reading and writing through OpenCV, with truncation checks and clear errors.
#pragma once
#include <opencv2/core.hpp>
#include <string>

namespace isplat {

// Reads any 8/16-bit grey, RGB or RGBA image as float32 RGB in [0, 1] (CV_32FC3).
// Missing, truncated or corrupt files throw Error naming the path and the problem.
cv::Mat read_image(const std::string& path);

// Reads a single-channel 16-bit PNG unchanged (CV_16UC1), e.g. depth in millimetres.
cv::Mat read_png16(const std::string& path);

// Writes float RGB in [0, 1] (CV_32FC3, clamped) or 8-bit RGB as PNG/JPG, atomically.
void write_image(const std::string& path, const cv::Mat& rgb, int jpeg_quality = 95);
// The same conversion on its own: float [0, 1] (clamped) or 8-bit RGB/grey -> 8-bit BGR/grey, as OpenCV's
// encoders and VideoWriter take it. `what` names the destination in errors.
cv::Mat rgb_to_bgr8(const cv::Mat& rgb, const std::string& what);
// Writes a CV_16UC1 image as 16-bit PNG, atomically.
void write_png16(const std::string& path, const cv::Mat& image16);

}  // namespace isplat
