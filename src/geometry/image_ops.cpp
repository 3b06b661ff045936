// Image and depth resizing/cropping with matching intrinsics updates.
#include "geometry/image_ops.h"

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstring>

#include "core/error.h"

namespace isplat {

CropBox center_crop_box(int width, int height, double aspect) {
  ISPLAT_CHECK(width > 0 && height > 0 && aspect > 0, "center_crop_box: bad size ", width, "x", height, " or aspect ",
               aspect);
  CropBox box{0, 0, width, height};
  if (static_cast<double>(width) / height > aspect) {
    box.width = std::max(1, static_cast<int>(std::lround(height * aspect)));
    box.x0 = (width - box.width) / 2;
  } else {
    box.height = std::max(1, static_cast<int>(std::lround(width / aspect)));
    box.y0 = (height - box.height) / 2;
  }
  return box;
}

cv::Mat resize_image(const cv::Mat& image, int width, int height) {
  ISPLAT_CHECK(!image.empty() && width > 0 && height > 0, "resize_image: empty image or bad size");
  if (image.cols == width && image.rows == height) return image.clone();
  const bool shrink = width < image.cols || height < image.rows;
  cv::Mat out;
  cv::resize(image, out, cv::Size(width, height), 0, 0, shrink ? cv::INTER_AREA : cv::INTER_LINEAR);
  return out;
}

cv::Mat resize_depth(const cv::Mat& depth, int width, int height) {
  ISPLAT_CHECK(!depth.empty() && width > 0 && height > 0, "resize_depth: empty depth or bad size");
  if (depth.cols == width && depth.rows == height) return depth.clone();
  // Nearest sample at each output pixel centre (OpenCV's INTER_NEAREST is off by half a pixel).
  cv::Mat out(height, width, depth.type());
  const double sx = static_cast<double>(depth.cols) / width, sy = static_cast<double>(depth.rows) / height;
  const size_t elem = depth.elemSize();
  for (int i = 0; i < height; ++i) {
    const int si = std::min(depth.rows - 1, static_cast<int>((i + 0.5) * sy));
    for (int j = 0; j < width; ++j) {
      const int sj = std::min(depth.cols - 1, static_cast<int>((j + 0.5) * sx));
      std::memcpy(out.ptr(i, j), depth.ptr(si, sj), elem);
    }
  }
  return out;
}

cv::Mat crop(const cv::Mat& image, const CropBox& box) {
  ISPLAT_CHECK(box.x0 >= 0 && box.y0 >= 0 && box.width > 0 && box.height > 0 && box.x0 + box.width <= image.cols &&
                   box.y0 + box.height <= image.rows,
               "crop: window outside the ", image.cols, "x", image.rows, " image");
  return image(cv::Rect(box.x0, box.y0, box.width, box.height)).clone();
}

void fit_view(cv::Mat& image, cv::Mat* depth, Intrinsics& intr, int width, int height) {
  ISPLAT_CHECK(image.cols == intr.width && image.rows == intr.height, "fit_view: image is ", image.cols, "x",
               image.rows, " but intrinsics say ", intr.width, "x", intr.height);
  const CropBox box = center_crop_box(image.cols, image.rows, static_cast<double>(width) / height);
  image = resize_image(crop(image, box), width, height);
  if (depth) {
    ISPLAT_CHECK(depth->cols == intr.width && depth->rows == intr.height, "fit_view: depth size differs from image");
    *depth = resize_depth(crop(*depth, box), width, height);
  }
  intr = intr.cropped(box.x0, box.y0, box.width, box.height).resized(width, height);
}

}  // namespace isplat
