// Resizing and cropping images and depth maps together with their intrinsics (OpenCV, data code).
#pragma once
#include <opencv2/core.hpp>

#include "geometry/camera.h"

namespace isplat {

struct CropBox {
  int x0 = 0, y0 = 0, width = 0, height = 0;
};

// Largest centred window of the given aspect ratio (width / height) inside a W x H image.
CropBox center_crop_box(int width, int height, double aspect);

// Colour: area averaging when shrinking, bilinear when enlarging.
cv::Mat resize_image(const cv::Mat& image, int width, int height);
// Depth: nearest neighbour, so values across a discontinuity are never blended.
cv::Mat resize_depth(const cv::Mat& depth, int width, int height);
cv::Mat crop(const cv::Mat& image, const CropBox& box);

// Centre-crop to the target aspect, then resize image (and depth, if given) to width x height,
// updating the intrinsics to match. The returned images own their memory.
void fit_view(cv::Mat& image, cv::Mat* depth, Intrinsics& intr, int width, int height);

}  // namespace isplat
