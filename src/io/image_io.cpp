// Image I/O: whole-file read, format sanity checks, size limits from the header, JPEG through libjpeg
// (corrupt data is an error), other formats through OpenCV, conversion to float RGB.
#include "io/image_io.h"

#include <jpeglib.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <csetjmp>
#include <cstdio>
#include <filesystem>

#include "core/error.h"
#include "core/runtime.h"
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

// "" when width x height is a size we decode, else why not.
std::string pixel_limit_problem(int64_t width, int64_t height) {
  const int64_t limit = max_image_pixels();
  if (width <= 0 || height <= 0) return cat("image header declares a size of ", width, "x", height);
  if (width > limit / height)
    return cat("image header declares ", width, "x", height, " pixels, more than the limit of ", limit,
               " (runtime.max_image_pixels)");
  return "";
}

void check_pixels(const std::string& path, int64_t width, int64_t height) {
  const std::string why = pixel_limit_problem(width, height);
  if (!why.empty()) fail(path, ": ", why);
}

// libjpeg reports corrupt scan data as a warning and fills the rest with grey; OpenCV hides those warnings.
// This error manager turns every warning into an error, so a damaged JPEG never decodes silently.
struct JpegErrors {
  jpeg_error_mgr mgr;
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
};

void jpeg_fail(j_common_ptr cinfo) {
  auto* errors = reinterpret_cast<JpegErrors*>(cinfo->err);
  cinfo->err->format_message(cinfo, errors->message);
  std::longjmp(errors->jump, 1);
}

void jpeg_message(j_common_ptr cinfo, int level) {
  if (level < 0) jpeg_fail(cinfo);  // a warning: corrupt data, premature end, extraneous bytes
}

// Naive CMYK -> RGB without a colour profile, as other readers (OpenCV, Pillow) do: R = (1 - C)(1 - K). With
// `inverted` (Adobe's convention) the stored values are already 1 - C and 1 - K.
cv::Mat cmyk_to_bgr(const cv::Mat& cmyk, bool inverted) {
  cv::Mat bgr(cmyk.rows, cmyk.cols, CV_8UC3);
  for (int i = 0; i < cmyk.rows; ++i) {
    const unsigned char* in = cmyk.ptr<unsigned char>(i);
    unsigned char* o = bgr.ptr<unsigned char>(i);
    for (int j = 0; j < cmyk.cols; ++j, in += 4, o += 3) {
      const int k = inverted ? in[3] : 255 - in[3];
      for (int c = 0; c < 3; ++c) {  // C, M, Y -> R, G, B, stored B, G, R
        const int ink_free = inverted ? in[c] : 255 - in[c];
        o[2 - c] = static_cast<unsigned char>((ink_free * k + 127) / 255);
      }
    }
  }
  return bgr;
}

// Decodes into `out` (8-bit BGR or grey, as cv::imdecode gives). Returns "" or the decoder's complaint.
// No object with a destructor lives between setjmp and the libjpeg calls that may longjmp back.
std::string decode_jpeg(const std::string& bytes, cv::Mat& out) {
  jpeg_decompress_struct cinfo;
  JpegErrors errors;
  cinfo.err = jpeg_std_error(&errors.mgr);
  errors.mgr.error_exit = jpeg_fail;
  errors.mgr.emit_message = jpeg_message;
  errors.message[0] = '\0';
  if (setjmp(errors.jump)) {
    jpeg_destroy_decompress(&cinfo);
    return errors.message[0] ? errors.message : "corrupt JPEG data";
  }
  jpeg_create_decompress(&cinfo);
  jpeg_mem_src(&cinfo, reinterpret_cast<const unsigned char*>(bytes.data()), static_cast<unsigned long>(bytes.size()));
  jpeg_read_header(&cinfo, TRUE);
  {  // refused from the header, before a pixel is allocated; the string is gone before libjpeg runs again
    const std::string too_large = pixel_limit_problem(cinfo.image_width, cinfo.image_height);
    if (!too_large.empty()) {
      jpeg_destroy_decompress(&cinfo);
      return too_large;
    }
  }
  const bool grey = cinfo.num_components == 1;
  // Print workflows save CMYK (or YCCK) JPEGs; libjpeg decodes them to CMYK only, converted to BGR below.
  const bool cmyk = cinfo.jpeg_color_space == JCS_CMYK || cinfo.jpeg_color_space == JCS_YCCK;
  const bool inverted = cmyk && cinfo.saw_Adobe_marker;  // Adobe's writers store CMYK inverted (255 = no ink)
  cinfo.out_color_space = grey ? JCS_GRAYSCALE : cmyk ? JCS_CMYK : JCS_EXT_BGR;
  jpeg_start_decompress(&cinfo);
  out.create(static_cast<int>(cinfo.output_height), static_cast<int>(cinfo.output_width),
             grey   ? CV_8UC1
             : cmyk ? CV_8UC4
                    : CV_8UC3);
  while (cinfo.output_scanline < cinfo.output_height) {
    JSAMPROW row = out.ptr<unsigned char>(static_cast<int>(cinfo.output_scanline));
    jpeg_read_scanlines(&cinfo, &row, 1);
  }
  jpeg_finish_decompress(&cinfo);
  jpeg_destroy_decompress(&cinfo);
  if (cmyk) out = cmyk_to_bgr(out, inverted);
  return "";
}

bool is_jpeg(const std::string& bytes) {
  return bytes.size() >= 2 && static_cast<unsigned char>(bytes[0]) == 0xFF &&
         static_cast<unsigned char>(bytes[1]) == 0xD8;
}

// PNG's IHDR chunk holds the size right after the signature: check it before OpenCV allocates.
void check_png_header(const std::string& path, const std::string& bytes) {
  if (bytes.size() < 24 || bytes.compare(12, 4, "IHDR") != 0) fail(path, ": PNG without an IHDR header chunk");
  auto be32 = [&](size_t at) {
    return (static_cast<int64_t>(static_cast<unsigned char>(bytes[at])) << 24) |
           (static_cast<int64_t>(static_cast<unsigned char>(bytes[at + 1])) << 16) |
           (static_cast<int64_t>(static_cast<unsigned char>(bytes[at + 2])) << 8) |
           static_cast<int64_t>(static_cast<unsigned char>(bytes[at + 3]));
  };
  check_pixels(path, be32(16), be32(20));
}

cv::Mat decode(const std::string& path, int flags) {
  ErrorContext context("decoding the image ", path);
  const std::string bytes = read_file_bytes(path);
  check_container(path, bytes);
  cv::Mat img;
  if (is_jpeg(bytes)) {
    const std::string why = decode_jpeg(bytes, img);
    if (!why.empty()) fail(path, ": ", why.rfind("image header", 0) == 0 ? "" : "corrupt JPEG: ", why);
    return img;
  }
  if (bytes.compare(0, 8, std::string("\x89PNG\r\n\x1a\n", 8)) == 0) check_png_header(path, bytes);
  cv::Mat buf(1, static_cast<int>(bytes.size()), CV_8UC1, const_cast<char*>(bytes.data()));
  try {
    img = cv::imdecode(buf, flags);
  } catch (const cv::Exception& e) {
    fail(path, ": cannot decode image: ", e.what());
  }
  if (img.empty()) fail(path, ": cannot decode image (corrupt or unsupported format)");
  check_pixels(path, img.cols, img.rows);
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
