// Valid input is read (issue 74, item 6): CMYK JPEGs, COLMAP image names with repeated spaces, PLY comments that
// contain the word end_header.
#include <catch2/catch.hpp>

#include <jpeglib.h>

#include <cstdio>
#include <filesystem>
#include <vector>

#include "core/error.h"
#include "data/colmap.h"
#include "io/image_io.h"
#include "io/ply.h"
#include "support/test_util.h"

using namespace isplat;
namespace fs = std::filesystem;

namespace {

// A 16x16 CMYK JPEG as Photoshop writes it (Adobe marker, values inverted: 255 = no ink): the left half red
// (no cyan, full magenta and yellow), the right half 50% grey (half black only).
std::string valid_cmyk_jpeg() {
  jpeg_compress_struct cinfo;
  jpeg_error_mgr err;
  cinfo.err = jpeg_std_error(&err);
  jpeg_create_compress(&cinfo);
  unsigned char* buffer = nullptr;
  unsigned long size = 0;
  jpeg_mem_dest(&cinfo, &buffer, &size);
  cinfo.image_width = 16;
  cinfo.image_height = 16;
  cinfo.input_components = 4;
  cinfo.in_color_space = JCS_CMYK;
  jpeg_set_defaults(&cinfo);
  jpeg_set_quality(&cinfo, 95, TRUE);
  jpeg_start_compress(&cinfo, TRUE);
  std::vector<unsigned char> row(16 * 4);
  for (int j = 0; j < 16; ++j) {
    const bool red = j < 8;
    const unsigned char ink[4] = {0, static_cast<unsigned char>(red ? 255 : 0),
                                  static_cast<unsigned char>(red ? 255 : 0), static_cast<unsigned char>(red ? 0 : 128)};
    for (int c = 0; c < 4; ++c) row[j * 4 + c] = static_cast<unsigned char>(255 - ink[c]);  // Adobe: inverted
  }
  while (cinfo.next_scanline < cinfo.image_height) {
    JSAMPROW r = row.data();
    jpeg_write_scanlines(&cinfo, &r, 1);
  }
  jpeg_finish_compress(&cinfo);
  std::string bytes(reinterpret_cast<char*>(buffer), size);
  jpeg_destroy_compress(&cinfo);
  std::free(buffer);
  return bytes;
}

}  // namespace

TEST_CASE("valid input: a CMYK JPEG reads as RGB", "[validinput][image]") {
  const std::string path = test::temp_dir("valid_cmyk") + "/cmyk.jpg";
  test::write_bytes(path, valid_cmyk_jpeg());
  const cv::Mat rgb = read_image(path);  // float RGB in [0, 1]
  REQUIRE(rgb.rows == 16);
  REQUIRE(rgb.cols == 16);
  REQUIRE(rgb.channels() == 3);
  const cv::Vec3f red = rgb.at<cv::Vec3f>(8, 2), grey = rgb.at<cv::Vec3f>(8, 13);
  CHECK(red[0] == Approx(1.0).margin(0.04));
  CHECK(red[1] == Approx(0.0).margin(0.04));
  CHECK(red[2] == Approx(0.0).margin(0.04));
  for (int c = 0; c < 3; ++c) CHECK(grey[c] == Approx(127.0 / 255).margin(0.04));
}

TEST_CASE("valid input: COLMAP image names keep repeated and inner spaces", "[validinput][colmap]") {
  const std::string dir = test::temp_dir("valid_colmap_spaces");
  test::write_bytes(dir + "/cameras.txt", "1 PINHOLE 64 48 50 50 32 24\n");
  test::write_bytes(dir + "/images.txt",
                    "1 1 0 0 0 0 0 0 1 holiday  photo   1.jpg\n\n"
                    "2 1 0 0 0 0.5 0 0 1 holiday photo 1.jpg  \n\n");
  const ColmapModel m = read_colmap_text(dir);
  CHECK(m.images.at(1).name == "holiday  photo   1.jpg");
  CHECK(m.images.at(2).name == "holiday photo 1.jpg");  // trailing blanks are not the name's
  // Written and read again: the same names.
  const std::string again = test::temp_dir("valid_colmap_spaces_again");
  write_colmap_text(again, m);
  CHECK(read_colmap_text(again).images.at(1).name == "holiday  photo   1.jpg");
}

TEST_CASE("valid input: a PLY comment containing end_header does not end the header", "[validinput][ply]") {
  const std::string dir = test::temp_dir("valid_ply_comment");
  torch::manual_seed(0);
  const Gaussians g{torch::randn({4, 3}), torch::rand({4, 3}) * 0.1 + 1e-3, torch::randn({4, 4}),
                    torch::rand({4, 3}) * 0.9 + 0.05, torch::rand({4}) * 0.9 + 0.05};
  PlyOptions options;
  options.comments = {"the line below is the real end_header", "end_header"};
  write_ply(dir + "/s.ply", g, false, options);
  // "comment end_header" is a comment; so is a comment that ends with the word.
  const Gaussians b = read_ply(dir + "/s.ply", false);
  CHECK(b.count() == 4);
  CHECK(torch::allclose(b.means, g.means));
  const auto comments = read_ply_comments(dir + "/s.ply");
  CHECK(std::count(comments.begin(), comments.end(), "end_header") == 1);
  CHECK(std::count(comments.begin(), comments.end(), "the line below is the real end_header") == 1);
}
