// Image I/O over OpenCV: whole-file read, format sanity checks, decode, convert to float RGB.
#include "io/image_io.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <filesystem>

#include "core/error.h"
#include "io/atomic_file.h"

namespace isplat {
namespace {

std::string lower_ext(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

bool tail_contains(const std::string& bytes, const std::string& marker, size_t window) {
  const size_t start = bytes.size() > window ? bytes.size() - window : 0;
  return bytes.find(marker, start) != std::string::npos;
}

// OpenCV happily decodes a truncated JPEG (grey fill) or partial PNG with a warning; refuse those.
void check_container(const std::string& path, const std::string& bytes) {
  if (bytes.empty()) fail(path, ": file is empty");
  static const std::string png_sig("\x89PNG\r\n\x1a\n", 8);
  if (bytes.compare(0, png_sig.size(), png_sig) == 0) {
    if (!tail_contains(bytes, "IEND", 64)) fail(path, ": truncated PNG (no IEND chunk at the end)");
    return;
  }
  if (bytes.size() >= 2 && static_cast<unsigned char>(bytes[0]) == 0xFF &&
      static_cast<unsigned char>(bytes[1]) == 0xD8) {
    if (!tail_contains(bytes, std::string("\xFF\xD9", 2), 64)) fail(path, ": truncated JPEG (no end-of-image marker)");
    return;
  }
  const std::string ext = lower_ext(path);
  if (ext == ".png" || ext == ".jpg" || ext == ".jpeg")
    fail(path, ": not a valid ", ext.substr(1), " file (bad signature)");
}

cv::Mat decode(const std::string& path, int flags) {
  const std::string bytes = read_file_bytes(path);
  check_container(path, bytes);
  cv::Mat buf(1, static_cast<int>(bytes.size()), CV_8UC1, const_cast<char*>(bytes.data()));
  cv::Mat img;
  try {
    img = cv::imdecode(buf, flags);
  } catch (const cv::Exception& e) {
    fail(path, ": cannot decode image: ", e.what());
  }
  if (img.empty()) fail(path, ": cannot decode image (corrupt or unsupported format)");
  return img;
}

void encode_and_write(const std::string& path, const cv::Mat& img, const std::vector<int>& params) {
  std::vector<uchar> out;
  const std::string ext = lower_ext(path);
  bool ok = false;
  try {
    ok = cv::imencode(ext.empty() ? ".png" : ext, img, out, params);
  } catch (const cv::Exception& e) {
    fail(path, ": cannot encode image: ", e.what());
  }
  if (!ok) fail(path, ": cannot encode image as ", ext);
  write_file_atomic(path, std::string(out.begin(), out.end()));
}

}  // namespace

cv::Mat read_image(const std::string& path) {
  cv::Mat img = decode(path, cv::IMREAD_UNCHANGED);
  double scale = 1.0;
  switch (img.depth()) {
    case CV_8U:
      scale = 1.0 / 255.0;
      break;
    case CV_16U:
      scale = 1.0 / 65535.0;
      break;
    case CV_32F:
      scale = 1.0;
      break;
    default:
      fail(path, ": unsupported pixel depth (", img.depth(), ")");
  }
  cv::Mat rgb;
  switch (img.channels()) {
    case 1:
      cv::cvtColor(img, rgb, cv::COLOR_GRAY2RGB);
      break;
    case 3:
      cv::cvtColor(img, rgb, cv::COLOR_BGR2RGB);
      break;
    case 4:
      cv::cvtColor(img, rgb, cv::COLOR_BGRA2RGB);
      break;
    default:
      fail(path, ": unsupported channel count ", img.channels());
  }
  cv::Mat out;
  rgb.convertTo(out, CV_32FC3, scale);
  return out;
}

cv::Mat read_png16(const std::string& path) {
  cv::Mat img = decode(path, cv::IMREAD_UNCHANGED);
  if (img.type() != CV_16UC1)
    fail(path, ": expected a single-channel 16-bit PNG, got ", img.channels(), " channel(s) of depth ", img.depth());
  return img;
}

cv::Mat rgb_to_bgr8(const cv::Mat& rgb, const std::string& what) {
  cv::Mat img8;
  if (rgb.depth() == CV_32F || rgb.depth() == CV_64F)
    rgb.convertTo(img8, CV_8U, 255.0, 0.0);  // saturate_cast rounds and clamps
  else if (rgb.depth() == CV_8U)
    img8 = rgb;
  else
    fail(what, ": expected float [0,1] or 8-bit image data");
  cv::Mat bgr;
  if (img8.channels() == 3)
    cv::cvtColor(img8, bgr, cv::COLOR_RGB2BGR);
  else if (img8.channels() == 1)
    bgr = img8;
  else
    fail(what, ": expected 1 or 3 channels, got ", img8.channels());
  return bgr;
}

void write_image(const std::string& path, const cv::Mat& rgb, int jpeg_quality) {
  ISPLAT_CHECK(!rgb.empty(), path, ": refusing to write an empty image");
  encode_and_write(path, rgb_to_bgr8(rgb, path), {cv::IMWRITE_JPEG_QUALITY, jpeg_quality});
}

void write_png16(const std::string& path, const cv::Mat& image16) {
  ISPLAT_CHECK(image16.type() == CV_16UC1, path, ": write_png16 expects CV_16UC1");
  encode_and_write(path, image16, {});
}

}  // namespace isplat
