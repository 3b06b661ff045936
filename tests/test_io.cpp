// File I/O: round trips (bit-exact where the format allows) and clear errors on bad files.
#include <catch2/catch.hpp>

#include <Imath/half.h>
#include <torch/torch.h>
#include <cmath>
#include <filesystem>
#include <limits>
#include <opencv2/core.hpp>

#include "core/error.h"
#include "io/atomic_file.h"
#include "io/csv.h"
#include "io/depth_io.h"
#include "io/hdf5_io.h"
#include "io/image_io.h"
#include "io/safetensors.h"
#include "io/tensor_image.h"
#include "support/test_util.h"

using namespace isplat;
using test::error_of;
namespace fs = std::filesystem;

namespace {

void truncate_file(const std::string& path, double keep_fraction) {
  const std::string bytes = test::read_bytes(path);
  test::write_bytes(path, bytes.substr(0, static_cast<size_t>(bytes.size() * keep_fraction)));
}

cv::Mat gradient_image(int h, int w) {
  cv::Mat img(h, w, CV_32FC3);
  for (int i = 0; i < h; ++i)
    for (int j = 0; j < w; ++j)
      img.at<cv::Vec3f>(i, j) = cv::Vec3f(j / float(w), i / float(h), ((i * 7 + j * 3) % 256) / 255.0f);
  return img;
}

}  // namespace

TEST_CASE("io: file fingerprints are size and FNV-1a 64, and tell content apart", "[io]") {
  const std::string dir = test::temp_dir("fingerprint");
  test::write_bytes(dir + "/empty", "");
  test::write_bytes(dir + "/a", "a");
  test::write_bytes(dir + "/b", "b");
  CHECK(file_fingerprint(dir + "/empty") == "0:cbf29ce484222325");  // the FNV-1a 64 offset basis
  CHECK(file_fingerprint(dir + "/a") == "1:af63dc4c8601ec8c");      // published FNV-1a 64 of "a"
  CHECK(file_fingerprint(dir + "/b") != file_fingerprint(dir + "/a"));
  const std::string big(3 << 20, 'x');  // spans several read blocks
  test::write_bytes(dir + "/big", big);
  CHECK(file_fingerprint(dir + "/big").rfind(std::to_string(big.size()) + ":", 0) == 0);
  CHECK_THAT(error_of([&] { file_fingerprint(dir + "/missing"); }), Catch::Contains(dir + "/missing: no such file"));
}

TEST_CASE("io: PNG round trip is exact at 8 bits, JPG is close", "[io][image]") {
  const auto dir = test::temp_dir("io_image");
  cv::Mat img = gradient_image(40, 60);
  write_image(dir + "/a.png", img);
  cv::Mat back = read_image(dir + "/a.png");
  REQUIRE(back.type() == CV_32FC3);
  REQUIRE(back.size() == img.size());
  double worst = cv::norm(back, img, cv::NORM_INF);
  CHECK(worst <= 0.5 / 255.0 + 1e-6);
  write_image(dir + "/a.jpg", img, 98);
  CHECK(cv::norm(read_image(dir + "/a.jpg"), img, cv::NORM_L1) / img.total() / 3 < 0.02);
  // Tensor conversion keeps channel order and values.
  auto t = image_to_tensor(back);
  CHECK(t.size(0) == 3);
  CHECK(t[0][5][7].item<float>() == back.at<cv::Vec3f>(5, 7)[0]);
  CHECK(cv::norm(tensor_to_image(t), back, cv::NORM_INF) == 0.0);

  cv::Mat d16(10, 12, CV_16UC1);
  for (int i = 0; i < d16.rows; ++i)
    for (int j = 0; j < d16.cols; ++j) d16.at<uint16_t>(i, j) = static_cast<uint16_t>(i * 5000 + j);
  write_png16(dir + "/d.png", d16);
  CHECK(cv::norm(read_png16(dir + "/d.png"), d16, cv::NORM_INF) == 0.0);
}

TEST_CASE("io: missing, truncated and corrupt images are named errors", "[io][image]") {
  const auto dir = test::temp_dir("io_image_bad");
  CHECK_THAT(error_of([&] { read_image(dir + "/none.png"); }), Catch::Contains("none.png: no such file"));
  cv::Mat img = gradient_image(64, 64);
  write_image(dir + "/t.png", img);
  truncate_file(dir + "/t.png", 0.6);
  CHECK_THAT(error_of([&] { read_image(dir + "/t.png"); }), Catch::Contains("t.png: truncated PNG"));
  write_image(dir + "/t.jpg", img);
  truncate_file(dir + "/t.jpg", 0.6);
  CHECK_THAT(error_of([&] { read_image(dir + "/t.jpg"); }), Catch::Contains("t.jpg: truncated JPEG"));
  test::write_bytes(dir + "/junk.png", "this is not an image at all");
  CHECK_THAT(error_of([&] { read_image(dir + "/junk.png"); }), Catch::Contains("junk.png: not a valid png"));
  test::write_bytes(dir + "/empty.jpg", "");
  CHECK_THAT(error_of([&] { read_image(dir + "/empty.jpg"); }), Catch::Contains("empty"));
}

TEST_CASE("io: EXR depth round trip is bit-exact and invalid depth is masked", "[io][exr]") {
  const auto dir = test::temp_dir("io_exr");
  cv::Mat depth(30, 40, CV_32FC1);
  for (int i = 0; i < depth.rows; ++i)
    for (int j = 0; j < depth.cols; ++j) depth.at<float>(i, j) = 0.1f + 0.123456789f * (i * depth.cols + j);
  depth.at<float>(1, 1) = std::numeric_limits<float>::quiet_NaN();
  depth.at<float>(2, 2) = std::numeric_limits<float>::infinity();
  depth.at<float>(3, 3) = 0.0f;
  depth.at<float>(4, 4) = -1.0f;
  write_depth_exr(dir + "/d.exr", depth);
  cv::Mat raw = read_exr_channel(dir + "/d.exr");
  for (int i = 0; i < depth.rows; ++i)
    for (int j = 0; j < depth.cols; ++j) {
      const float a = depth.at<float>(i, j), b = raw.at<float>(i, j);
      if (std::isnan(a))
        CHECK(std::isnan(b));
      else
        CHECK(std::memcmp(&a, &b, sizeof(float)) == 0);
    }
  DepthMap dm = read_depth_exr(dir + "/d.exr");
  CHECK(dm.invalid_count == 4);
  CHECK(dm.valid.at<uint8_t>(1, 1) == 0);
  CHECK(dm.depth.at<float>(1, 1) == 0.0f);
  CHECK(dm.valid.at<uint8_t>(5, 5) == 1);
  CHECK(cv::checkRange(dm.depth));  // no NaN/inf left

  CHECK_THAT(error_of([&] { read_exr_channel(dir + "/d.exr", "Q"); }), Catch::Contains("no channel 'Q'"));
  CHECK_THAT(error_of([&] { read_depth_exr(dir + "/none.exr"); }), Catch::Contains("none.exr: no such file"));
  fs::copy_file(dir + "/d.exr", dir + "/t.exr");
  truncate_file(dir + "/t.exr", 0.5);
  CHECK_THAT(error_of([&] { read_depth_exr(dir + "/t.exr"); }), Catch::Contains("t.exr"));
  test::write_bytes(dir + "/junk.exr", "garbage garbage garbage");
  CHECK_THAT(error_of([&] { read_depth_exr(dir + "/junk.exr"); }), Catch::Contains("junk.exr: cannot read EXR"));
}

TEST_CASE("io: HDF5 round trips for every stored type, float16 converted by us", "[io][hdf5]") {
  const auto dir = test::temp_dir("io_hdf5");
  std::vector<float> values = {3.9999998f,  1.0f,        -2.5f,      0.0f,   65504.0f, 1e-3f,
                               7.0f / 3.0f, 0.99999994f, 1.9999999f, 100.1f, -0.333f,  8.0f};
  write_hdf5(dir + "/h.hdf5", {3, 4}, values.data(), H5Type::Float16);
  auto h = read_hdf5_float(dir + "/h.hdf5");
  CHECK(h.stored == H5Type::Float16);
  CHECK(h.shape == std::vector<int64_t>{3, 4});
  for (size_t i = 0; i < values.size(); ++i) CHECK(h.values[i] == static_cast<float>(Imath::half(values[i])));
  CHECK(h.values[0] == 4.0f);  // HDF5's own conversion would give 2.0 here
  CHECK(h.values[8] == 2.0f);

  write_hdf5(dir + "/f.hdf5", {12}, values.data(), H5Type::Float32, 0);
  auto f = read_hdf5_float(dir + "/f.hdf5");
  CHECK(std::memcmp(f.values.data(), values.data(), values.size() * sizeof(float)) == 0);

  std::vector<double> dv = {1.0 / 3.0, -1e300, 2.5e-10, 42.0, 0.1, 0.2};
  write_hdf5(dir + "/d.hdf5", {2, 3}, dv.data(), H5Type::Float64);
  auto d = read_hdf5_double(dir + "/d.hdf5");
  CHECK(d.values == dv);
  CHECK(d.numel() == 6);

  std::vector<int64_t> iv = {-32768, -1, 0, 1, 32767, 1234};
  write_hdf5(dir + "/i.hdf5", {6}, iv.data(), H5Type::Int16);
  auto i16 = read_hdf5_int(dir + "/i.hdf5");
  CHECK(i16.stored == H5Type::Int16);
  CHECK(i16.values == iv);

  // gzip really compresses a smooth field.
  std::vector<float> big(256 * 256, 1.5f);
  write_hdf5(dir + "/z.hdf5", {256, 256}, big.data(), H5Type::Float16, 4);
  write_hdf5(dir + "/u.hdf5", {256, 256}, big.data(), H5Type::Float16, 0);
  CHECK(fs::file_size(dir + "/z.hdf5") * 4 < fs::file_size(dir + "/u.hdf5"));
  CHECK(read_hdf5_float(dir + "/z.hdf5").values == read_hdf5_float(dir + "/u.hdf5").values);
}

TEST_CASE("io: HDF5 errors name the file and the problem", "[io][hdf5]") {
  const auto dir = test::temp_dir("io_hdf5_bad");
  std::vector<int64_t> iv = {1, 2, 3};
  write_hdf5(dir + "/i.hdf5", {3}, iv.data(), H5Type::Int16);
  CHECK_THAT(error_of([&] { read_hdf5_float(dir + "/i.hdf5"); }),
             Catch::Contains("has type int16; expected a floating-point dataset"));
  CHECK_THAT(error_of([&] { read_hdf5_float(dir + "/i.hdf5", "depth"); }), Catch::Contains("no dataset named 'depth'"));
  CHECK_THAT(error_of([&] { read_hdf5_float(dir + "/none.hdf5"); }), Catch::Contains("none.hdf5: no such file"));
  test::write_bytes(dir + "/junk.hdf5", std::string(4096, 'x'));
  CHECK_THAT(error_of([&] { read_hdf5_float(dir + "/junk.hdf5"); }), Catch::Contains("junk.hdf5: not an HDF5 file"));
  std::vector<float> big(200 * 200);
  for (size_t k = 0; k < big.size(); ++k) big[k] = std::sin(k * 0.37f) * 100.0f;
  write_hdf5(dir + "/t.hdf5", {200, 200}, big.data(), H5Type::Float32, 0);
  truncate_file(dir + "/t.hdf5", 0.5);
  CHECK_THAT(error_of([&] { read_hdf5_float(dir + "/t.hdf5"); }), Catch::Contains("t.hdf5"));
}

TEST_CASE("io: safetensors round trip for F32, F16, BF16, I64 is bit-exact", "[io][safetensors]") {
  const auto dir = test::temp_dir("io_st");
  std::map<std::string, torch::Tensor> ts = {
      {"a.weight", torch::randn({3, 5})},
      {"b.half", torch::randn({7}).to(torch::kFloat16)},
      {"c.bf16", torch::randn({2, 2, 2}).to(torch::kBFloat16)},
      {"d.index", torch::arange(-5, 6, torch::kInt64)},
      {"e.scalar", torch::tensor(3.5f)},
  };
  write_safetensors(dir + "/m.safetensors", ts, {{"format", "pt"}});
  auto back = read_safetensors(dir + "/m.safetensors");
  CHECK(back.metadata.at("format") == "pt");
  REQUIRE(back.tensors.size() == ts.size());
  for (const auto& [name, t] : ts) {
    const auto& b = back.at(name);
    CHECK(b.scalar_type() == t.scalar_type());
    CHECK(b.sizes() == t.sizes());
    CHECK(std::memcmp(b.data_ptr(), t.contiguous().data_ptr(), t.numel() * t.element_size()) == 0);
  }
  // Header is 8-byte aligned, as the reference implementation writes it.
  const std::string bytes = test::read_bytes(dir + "/m.safetensors");
  uint64_t n = 0;
  std::memcpy(&n, bytes.data(), 8);
  CHECK(n % 8 == 0);
  CHECK_THAT(error_of([&] { back.at("nope"); }), Catch::Contains("no tensor named 'nope'"));
}

TEST_CASE("io: corrupt safetensors are named errors", "[io][safetensors]") {
  const auto dir = test::temp_dir("io_st_bad");
  write_safetensors(dir + "/m.safetensors", {{"w", torch::randn({64, 64})}});
  const std::string good = test::read_bytes(dir + "/m.safetensors");
  CHECK_THAT(error_of([&] { read_safetensors(dir + "/none.safetensors"); }), Catch::Contains("no such file"));
  test::write_bytes(dir + "/t.safetensors", good.substr(0, good.size() - 100));
  CHECK_THAT(error_of([&] { read_safetensors(dir + "/t.safetensors"); }), Catch::Contains("outside"));
  test::write_bytes(dir + "/short.safetensors", good.substr(0, 5));
  CHECK_THAT(error_of([&] { read_safetensors(dir + "/short.safetensors"); }), Catch::Contains("truncated"));
  std::string huge = good;
  huge[7] = '\x7f';
  test::write_bytes(dir + "/len.safetensors", huge);
  CHECK_THAT(error_of([&] { read_safetensors(dir + "/len.safetensors"); }), Catch::Contains("header length"));
  std::string badjson = good;
  badjson[8] = '#';
  test::write_bytes(dir + "/json.safetensors", badjson);
  CHECK_THAT(error_of([&] { read_safetensors(dir + "/json.safetensors"); }),
             Catch::Contains("safetensors header") && Catch::Contains("invalid JSON"));
  std::string shape = good;
  const auto pos = shape.find("[64,64]");
  REQUIRE(pos != std::string::npos);
  shape.replace(pos, 7, "[64,63]");
  test::write_bytes(dir + "/shape.safetensors", shape);
  CHECK_THAT(error_of([&] { read_safetensors(dir + "/shape.safetensors"); }), Catch::Contains("shape and dtype need"));
}

TEST_CASE("io: CSV parsing handles quotes and reports bad rows", "[io][csv]") {
  auto t = parse_csv("name,value,flag\r\nai_001_001,0.0254,True\n\"a, \"\"quoted\"\"\",2,False\n\n", "mem.csv");
  CHECK(t.size() == 2);
  CHECK(t.cell(1, "name") == "a, \"quoted\"");
  CHECK(t.number(0, "value") == Approx(0.0254));
  CHECK(t.boolean(0, "flag"));
  CHECK_FALSE(t.boolean(1, "flag"));
  CHECK_THAT(error_of([&] { t.number(0, "name"); }), Catch::Contains("mem.csv: data row 1, column 'name'"));
  CHECK_THAT(error_of([&] { t.cell(0, "nope"); }), Catch::Contains("missing column 'nope'"));
  CHECK_THAT(error_of([&] { parse_csv("a,b\n1,2\n3\n", "r.csv"); }), Catch::Contains("r.csv: line 3 has 1 fields"));
  const auto dir = test::temp_dir("io_csv");
  write_csv(dir + "/t.csv", t);
  auto back = read_csv(dir + "/t.csv");
  CHECK(back.rows == t.rows);
  CHECK(back.header == t.header);
}

TEST_CASE("io: atomic writes leave the old file when the writer fails", "[io][atomic]") {
  const auto dir = test::temp_dir("io_atomic");
  const std::string path = dir + "/ckpt.bin";
  write_file_atomic(path, std::string("old contents"));
  CHECK_THROWS(write_file_atomic(path, [](std::ostream& os) {
    os << "partial";
    throw Error("simulated crash mid-write");
  }));
  CHECK(test::read_bytes(path) == "old contents");
  size_t files = 0;
  for (const auto& e : fs::directory_iterator(dir)) files += e.is_regular_file();
  CHECK(files == 1);                                          // no temporary left behind
  write_file_atomic(dir + "/sub/new.txt", std::string("x"));  // parent folders are created
  CHECK(test::read_bytes(dir + "/sub/new.txt") == "x");
  {
    AtomicPath p(dir + "/never.png");
    test::write_bytes(p.temp(), "abc");
  }  // not committed -> removed
  CHECK_FALSE(fs::exists(dir + "/never.png"));
}
