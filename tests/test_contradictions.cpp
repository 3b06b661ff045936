// Contradictory input is an error naming the file and the place, never a silent repair (issue 74, item 4):
// repeated COLMAP ids and names, duplicated or non-rigid nerfstudio frames, PLY vertices that cannot be a Gaussian.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "core/error.h"
#include "data/colmap.h"
#include "data/nerfstudio.h"
#include "io/ply.h"
#include "support/test_util.h"
#include "support/tiny_dataset.h"

using namespace isplat;
using test::error_of;
namespace fs = std::filesystem;

namespace {

// Two PINHOLE cameras and two images without keypoints, as text.
void contra_write_text_model(const std::string& dir, const std::string& cameras_extra,
                             const std::string& images_extra) {
  fs::create_directories(dir);
  test::write_bytes(dir + "/cameras.txt",
                    "# cameras\n1 PINHOLE 64 48 50 50 32 24\n2 PINHOLE 64 48 60 60 32 24\n" + cameras_extra);
  test::write_bytes(dir + "/images.txt",
                    "# images\n1 1 0 0 0 0 0 0 1 a.png\n\n2 1 0 0 0 0.5 0 0 2 b.png\n\n" + images_extra);
}

// The same model in binary, written by the project's writer (ids 1, 2; names a.png, b.png).
ColmapModel contra_model() {
  ColmapModel m;
  m.cameras[1] = {1, 1, 64, 48, {50, 50, 32, 24}};
  m.cameras[2] = {2, 1, 64, 48, {60, 60, 32, 24}};
  for (int64_t id : {1, 2}) {
    ColmapImage img;
    img.id = id;
    img.camera_id = id;
    img.name = id == 1 ? "a.png" : "b.png";
    m.images[id] = img;
  }
  return m;
}

// Overwrites `bytes` at `at` with the little-endian uint32 `v`.
void contra_put_u32(std::string& bytes, size_t at, uint32_t v) {
  for (int k = 0; k < 4; ++k) bytes[at + k] = static_cast<char>((v >> (8 * k)) & 0xff);
}

std::string contra_ns_scene(const GenerateOptions& g) {
  return generated_eval_root(g.out, "atrium_nerfstudio") + "/scene_0";
}

// A PLY of `n` vertices in the 3DGS layout, all values from `value(vertex, property)`, plus `tail` bytes.
std::string contra_ply(int n, const std::function<float(int, int)>& value, const std::string& tail = "",
                       const std::string& comment = "") {
  const char* names[] = {"x",       "y",       "z",       "nx",      "ny",    "nz",    "f_dc_0", "f_dc_1", "f_dc_2",
                         "opacity", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2",  "rot_3"};
  std::string h = "ply\nformat binary_little_endian 1.0\n" + comment + "element vertex " + std::to_string(n) + "\n";
  for (const char* p : names) h += std::string("property float ") + p + "\n";
  h += "end_header\n";
  for (int v = 0; v < n; ++v)
    for (int k = 0; k < 17; ++k) {
      const float x = value(v, k);
      h.append(reinterpret_cast<const char*>(&x), 4);
    }
  return h + tail;
}

// A valid Gaussian's property k: at z = 2, small, opaque, identity rotation.
float contra_valid(int v, int k) {
  if (k == 2) return 2.0f;
  if (k >= 10 && k <= 12) return -3.0f;
  if (k == 13) return 1.0f;
  return k == 0 ? 0.1f * v : 0.0f;
}

// What the code writes to stderr while `f` runs.
std::string contra_stderr_of(const std::function<void()>& f) {
  std::fflush(stderr);
  const std::string path = test::temp_dir("contra_stderr") + "/err.txt";
  const int saved = ::dup(2);
  std::FILE* file = std::fopen(path.c_str(), "w");
  ::dup2(::fileno(file), 2);
  f();
  std::fflush(stderr);
  ::dup2(saved, 2);
  ::close(saved);
  std::fclose(file);
  return test::read_bytes(path);
}

}  // namespace

TEST_CASE("contradictions: a COLMAP text model defining a camera id, image id or image name twice is refused",
          "[contradictions][colmap]") {
  const std::string base = test::temp_dir("contra_colmap_text");
  contra_write_text_model(base + "/ok", "", "");
  CHECK(read_colmap_text(base + "/ok").images.size() == 2);

  contra_write_text_model(base + "/cam", "1 PINHOLE 64 48 70 70 32 24\n", "");
  CHECK_THAT(error_of([&] { read_colmap_text(base + "/cam"); }), Catch::Contains("cameras.txt") &&
                                                                     Catch::Contains("camera id 1 is defined twice") &&
                                                                     Catch::Contains("line 2 and line 4"));

  contra_write_text_model(base + "/id", "", "2 1 0 0 0 0.9 0 0 1 c.png\n\n");
  CHECK_THAT(error_of([&] { read_colmap_text(base + "/id"); }), Catch::Contains("images.txt") &&
                                                                    Catch::Contains("image id 2 is defined twice") &&
                                                                    Catch::Contains("line 4 and line 6"));

  contra_write_text_model(base + "/name", "", "3 1 0 0 0 0.9 0 0 1 a.png\n\n");
  CHECK_THAT(error_of([&] { read_colmap_text(base + "/name"); }),
             Catch::Contains("images.txt") && Catch::Contains("image name 'a.png' is defined twice") &&
                 Catch::Contains("line 2 and line 6"));
}

TEST_CASE("contradictions: a COLMAP binary model defining a camera id, image id or image name twice is refused",
          "[contradictions][colmap]") {
  const std::string dir = test::temp_dir("contra_colmap_bin");
  write_colmap_binary(dir, contra_model());
  const std::string cameras = test::read_bytes(dir + "/cameras.bin"), images = test::read_bytes(dir + "/images.bin");
  REQUIRE(read_colmap_binary(dir).images.size() == 2);

  // cameras.bin: a count, then per camera id (4), model (4), width (8), height (8), 4 doubles: 56 bytes.
  std::string cam = cameras;
  contra_put_u32(cam, 8 + 56, 1);
  test::write_bytes(dir + "/cameras.bin", cam);
  CHECK_THAT(error_of([&] { read_colmap_binary(dir); }),
             Catch::Contains("cameras.bin") && Catch::Contains("camera id 1 is defined twice (entry 0 and entry 1)"));
  test::write_bytes(dir + "/cameras.bin", cameras);

  // images.bin: per image id (4), 7 doubles, camera id (4), the name and its NUL, the keypoint count (8).
  const size_t second = 8 + 4 + 56 + 4 + 6 + 8;
  std::string ids = images;
  contra_put_u32(ids, second, 1);
  test::write_bytes(dir + "/images.bin", ids);
  CHECK_THAT(error_of([&] { read_colmap_binary(dir); }),
             Catch::Contains("images.bin") && Catch::Contains("image id 1 is defined twice (entry 0 and entry 1)"));

  std::string names = images;
  REQUIRE(names.substr(second + 4 + 56 + 4, 5) == "b.png");
  names[second + 4 + 56 + 4] = 'a';
  test::write_bytes(dir + "/images.bin", names);
  CHECK_THAT(error_of([&] { read_colmap_binary(dir); }),
             Catch::Contains("images.bin") && Catch::Contains("image name 'a.png' is defined twice"));
}

TEST_CASE("contradictions: nerfstudio frames naming one image twice, or poses that are not rigid, are refused",
          "[contradictions][nerfstudio]") {
  const auto g = test::make_tiny_dataset("contra_ns");
  const std::string scene = contra_ns_scene(g), file = scene + "/transforms.json";
  const auto original = nlohmann::json::parse(test::read_bytes(file));
  REQUIRE(nerfstudio_sequence(scene, "x").frames.size() == original["frames"].size());
  const auto with = [&](const std::function<void(nlohmann::json&)>& change) {
    auto j = original;
    change(j);
    test::write_bytes(file, j.dump());
    return error_of([&] { nerfstudio_sequence(scene, "x"); });
  };
  // The same image twice, once spelled with "./": two poses for one photo.
  CHECK_THAT(with([](nlohmann::json& j) {
               auto copy = j["frames"][0];
               copy["file_path"] = "./" + copy["file_path"].get<std::string>();
               j["frames"].push_back(copy);
             }),
             Catch::Contains("transforms.json") && Catch::Contains("both name the image") &&
                 Catch::Contains("duplicated frame"));
  // A scaled rotation column, a mirror, a bottom row that is not 0 0 0 1.
  CHECK_THAT(with([](nlohmann::json& j) {
               for (int r = 0; r < 3; ++r)
                 j["frames"][1]["transform_matrix"][r][0] =
                     2.0 * j["frames"][1]["transform_matrix"][r][0].get<double>();
             }),
             Catch::Contains("transforms.json frame") && Catch::Contains("is not a rotation") &&
                 Catch::Contains("orthonormal"));
  CHECK_THAT(with([](nlohmann::json& j) {
               for (int r = 0; r < 3; ++r)
                 j["frames"][1]["transform_matrix"][r][0] = -j["frames"][1]["transform_matrix"][r][0].get<double>();
             }),
             Catch::Contains("transforms.json frame") && Catch::Contains("it mirrors"));
  CHECK_THAT(with([](nlohmann::json& j) { j["frames"][2]["transform_matrix"][3][0] = 0.5; }),
             Catch::Contains("transforms.json frame") && Catch::Contains("last row"));
  test::write_bytes(file, original.dump());
}

TEST_CASE("contradictions: PLY vertices with a zero quaternion or an overflowing scale are refused by vertex",
          "[contradictions][ply]") {
  const std::string dir = test::temp_dir("contra_ply");
  test::write_bytes(dir + "/ok.ply", contra_ply(3, contra_valid));
  CHECK(read_ply(dir + "/ok.ply").count() == 3);

  test::write_bytes(dir + "/zero_quat.ply",
                    contra_ply(3, [](int v, int k) { return v == 1 && k == 13 ? 0.0f : contra_valid(v, k); }));
  CHECK_THAT(error_of([&] { read_ply(dir + "/zero_quat.ply"); }),
             Catch::Contains("zero_quat.ply: vertex 1 has a zero rotation quaternion"));

  test::write_bytes(dir + "/huge_scale.ply",
                    contra_ply(3, [](int v, int k) { return v == 2 && k == 11 ? 100.0f : contra_valid(v, k); }));
  CHECK_THAT(error_of([&] { read_ply(dir + "/huge_scale.ply"); }),
             Catch::Contains("huge_scale.ply: vertex 2 property 'scale_1'") && Catch::Contains("overflows"));
}

TEST_CASE("contradictions: data after a PLY's declared vertices is reported with its size", "[contradictions][ply]") {
  test::QuietLogs quiet;  // warnings still show
  const std::string dir = test::temp_dir("contra_ply_tail");
  // Five vertices written, three declared: what a writer that lost count leaves.
  const std::string five = contra_ply(5, contra_valid);
  std::string three = contra_ply(3, contra_valid);
  three += five.substr(five.size() - 2 * 17 * 4);
  test::write_bytes(dir + "/tail.ply", three);
  Gaussians g;
  const std::string err = contra_stderr_of([&] { g = read_ply(dir + "/tail.ply"); });
  CHECK(g.count() == 3);
  CHECK_THAT(err, Catch::Contains("tail.ply") && Catch::Contains("136 bytes (2 vertices' worth) after the 3 declared"));
  // A file without extra data says nothing.
  test::write_bytes(dir + "/exact.ply", contra_ply(3, contra_valid));
  CHECK(contra_stderr_of([&] { read_ply(dir + "/exact.ply"); }).find("declared") == std::string::npos);
}
