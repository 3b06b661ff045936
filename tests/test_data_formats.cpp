// COLMAP (text/binary) and nerfstudio readers on generated scenes, the camera-model table, and bad input.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>

#include "core/error.h"
#include "data/colmap.h"
#include "data/nerfstudio.h"
#include "io/atomic_file.h"
#include "support/consistency.h"
#include "support/test_util.h"
#include "support/tiny_dataset.h"

using namespace isplat;
using test::error_of;
namespace fs = std::filesystem;

namespace {
std::string colmap_scene(const GenerateOptions& g) {
  return generated_eval_root(g.out, "courtyard_colmap") + "/scene_0";
}
std::string ns_scene(const GenerateOptions& g) {
  return generated_eval_root(g.out, "atrium_nerfstudio") + "/scene_0";
}
}  // namespace

TEST_CASE("colmap: text and binary models are identical", "[data][colmap]") {
  const auto g = test::make_tiny_dataset("colmap_parity");
  const std::string sparse = colmap_scene(g) + "/sparse/0";
  const ColmapModel t = read_colmap_text(sparse), b = read_colmap_binary(sparse);
  REQUIRE(t.images.size() == 8);
  CHECK(t.points.size() > 10);
  CHECK(t.cameras.size() == b.cameras.size());
  CHECK(t.cameras.at(1).params == b.cameras.at(1).params);
  for (const auto& [id, img] : t.images) {
    const auto& o = b.images.at(id);
    CHECK(img.name == o.name);
    CHECK((img.qvec - o.qvec).norm() == 0.0);
    CHECK((img.tvec - o.tvec).norm() == 0.0);
    CHECK(img.point3D_ids == o.point3D_ids);
    REQUIRE(img.xys.size() == o.xys.size());
    for (size_t k = 0; k < img.xys.size(); ++k) CHECK((img.xys[k] - o.xys[k]).norm() == 0.0);
  }
  for (const auto& [id, p] : t.points) {
    CHECK((p.xyz - b.points.at(id).xyz).norm() == 0.0);
    CHECK(p.track == b.points.at(id).track);
  }
  // Every track entry points back at its keypoint.
  for (const auto& [id, p] : t.points)
    for (const auto& [image_id, idx] : p.track) CHECK(t.images.at(image_id).point3D_ids.at(idx) == id);
}

TEST_CASE("colmap: a real-format fixture parses, including an empty POINTS2D line", "[data][colmap]") {
  const auto dir = test::temp_dir("colmap_fixture");
  test::write_bytes(dir + "/cameras.txt",
                    "# Camera list with one line of data per camera:\n"
                    "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
                    "# Number of cameras: 2\n"
                    "1 SIMPLE_RADIAL 3072 2304 2559.81 1536 1152 -0.0204997\n"
                    "2 PINHOLE 6048 4032 3410.34 3409.98 3033.34 2009.99\n");
  test::write_bytes(dir + "/images.txt",
                    "# Image list with two lines of data per image:\n"
                    "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
                    "#   POINTS2D[] as (X, Y, POINT3D_ID)\n"
                    "# Number of images: 2, mean observations per image: 1\n"
                    "1 0.851773 0.0165051 0.503764 -0.142941 -0.737434 1.02973 3.74354 1 P1180141.JPG\n"
                    "2362.39 248.498 1 1784.7 268.254 -1\n"
                    "2 0.851773 0.0165051 0.503764 -0.142941 -0.737434 1.02973 3.74354 2 dslr images/P1180142.JPG\n"
                    "\n");
  test::write_bytes(dir + "/points3D.txt",
                    "# 3D point list with one line of data per point:\n"
                    "1 1.0 2.0 3.0 255 128 0 0.5 1 0\n");
  const ColmapModel m = read_colmap(dir);
  CHECK(m.cameras.at(1).model_id == 2);
  CHECK(m.images.at(1).xys.size() == 2);
  CHECK(m.images.at(1).point3D_ids[1] == -1);
  CHECK(m.images.at(2).name == "dslr images/P1180142.JPG");
  CHECK(m.images.at(2).xys.empty());
  CHECK(m.points.at(1).rgb[1] == 128);
  std::vector<double> dist;
  const Intrinsics k = colmap_intrinsics(m.cameras.at(1), dist);
  CHECK(k.fx == Approx(2559.81));
  CHECK(k.cy == Approx(1152));
  CHECK(dist == std::vector<double>{-0.0204997, 0, 0, 0});
  colmap_intrinsics(m.cameras.at(2), dist);
  CHECK(dist.empty());
}

TEST_CASE("colmap: every camera model id has its parameter count, distortion is handled or refused", "[data][colmap]") {
  const int counts[] = {3, 4, 4, 5, 8, 8, 12, 5, 4, 5, 12, 16};
  for (int id = 0; id < 12; ++id) {
    REQUIRE(colmap_model_by_id(id));
    CHECK(colmap_model_by_id(id)->num_params == counts[id]);
    CHECK(colmap_model_by_name(colmap_model_by_id(id)->name)->id == id);
  }
  CHECK(colmap_model_by_id(42) == nullptr);
  std::vector<double> dist;
  ColmapCamera fisheye{1, 5, 100, 80, {50, 50, 50, 40, 0.1, 0, 0, 0}};
  CHECK_THROWS_WITH(colmap_intrinsics(fisheye, dist), Catch::Contains("OPENCV_FISHEYE has non-zero distortion"));
  fisheye.params = {50, 50, 50, 40, 0, 0, 0, 0};
  CHECK(colmap_intrinsics(fisheye, dist).fx == 50.0);
  ColmapCamera opencv{2, 4, 100, 80, {60, 61, 50, 40, 0.1, -0.01, 0.001, 0.002}};
  CHECK(colmap_intrinsics(opencv, dist).fy == 61.0);
  CHECK(dist.size() == 4);
  ColmapCamera wrong{3, 1, 100, 80, {60, 61, 50}};
  CHECK_THROWS_WITH(colmap_intrinsics(wrong, dist), Catch::Contains("PINHOLE needs 4 parameters, got 3"));
}

TEST_CASE("colmap: a hall evaluation set is written in the evaluation format, and unknown styles are refused",
          "[data][colmap]") {
  test::QuietLogs quiet;
  auto g = test::eval_dataset_options(test::temp_dir("colmap_hall"), 4, {"hall_colmap"});
  generate_datasets(g);
  const Sequence seq =
      colmap_sequence(generated_eval_root(g.out, "hall_colmap") + "/scene_0", "hall", ColmapSceneLayout{});
  REQUIRE(seq.frames.size() == 4);
  const LoadedFrame fr = load_frame(seq, 0);
  REQUIRE(fr.has_depth());
  CHECK(fr.image.cols == g.eval_width);
  double deepest = 0;
  cv::minMaxLoc(fr.depth.depth, nullptr, &deepest, nullptr, nullptr, fr.depth.valid);
  CHECK(deepest > 10.0);  // a hall, not a room (at most 11 m deep, seen from inside)
  g.eval_datasets = {"desk_colmap"};
  CHECK_THROWS_WITH(generate_datasets(g), Catch::Contains("'desk_colmap' must be <courtyard|atrium|room|hall>"));
}

TEST_CASE("colmap: generated scene reads as a consistent sequence with EXR depth", "[data][colmap]") {
  const auto g = test::make_tiny_dataset("colmap_seq");
  const Sequence seq = colmap_sequence(colmap_scene(g), "courtyard", ColmapSceneLayout{});
  REQUIRE(seq.frames.size() == 8);
  CHECK(seq.frames[0].depth == DepthSource::PlanarExr);
  const LoadedFrame a = load_frame(seq, 0), b = load_frame(seq, 2);
  const auto c = test::depth_consistency(a, b, 0.01, 1);
  INFO("checked " << c.checked << " agree " << c.agree << " median " << c.median_rel);
  CHECK(c.checked > 200);
  CHECK(c.agree > 0.85);
  CHECK(c.median_rel < 1e-3);  // float32 EXR depth
  // Sparse prompts from points3D land at their observed depth.
  const ColmapModel model = read_colmap(colmap_scene(g) + "/sparse/0");
  const auto prompts = colmap_sparse_depth(model, a.view);
  REQUIRE(prompts.size() > 5);
  int agree = 0;
  for (const auto& p : prompts) {
    const int u = static_cast<int>(p.x()), v = static_cast<int>(p.y());
    agree += a.depth.valid.at<uint8_t>(v, u) && std::fabs(a.depth.depth.at<float>(v, u) - p.z()) < 0.05 * p.z();
  }
  CHECK(agree > static_cast<int>(prompts.size()) / 2);
}

TEST_CASE("colmap: bad input names the problem", "[data][colmap]") {
  const auto g = test::make_tiny_dataset("colmap_bad");
  const std::string scene = colmap_scene(g), sparse = scene + "/sparse/0";
  fs::remove(scene + "/images/IMG_0003.jpg");
  CHECK_THAT(error_of([&] { colmap_sequence(scene, "x", ColmapSceneLayout{}); }),
             Catch::Contains("images names 'IMG_0003.jpg'") && Catch::Contains("does not exist"));
  // Camera id mismatch: images refer to a camera that cameras.txt does not define.
  fs::remove(sparse + "/cameras.bin");
  std::string cams = test::read_bytes(sparse + "/cameras.txt");
  cams.replace(cams.find("\n1 PINHOLE"), 10, "\n7 PINHOLE");
  test::write_bytes(sparse + "/cameras.txt", cams);
  fs::remove(sparse + "/images.bin");
  CHECK_THAT(error_of([&] { read_colmap(sparse); }),
             Catch::Contains("refers to camera 1, which cameras does not define"));
  // Truncated binary.
  const auto dir2 = test::temp_dir("colmap_trunc");
  ColmapModel m;
  m.cameras[1] = {1, 1, 10, 10, {5, 5, 5, 5}};
  write_colmap_binary(dir2, m);
  const std::string bytes = test::read_bytes(dir2 + "/cameras.bin");
  test::write_bytes(dir2 + "/cameras.bin", bytes.substr(0, bytes.size() - 8));
  CHECK_THAT(error_of([&] { read_colmap_binary(dir2); }), Catch::Contains("cameras.bin: truncated"));
  // An empty sequence.
  const auto dir3 = test::temp_dir("colmap_empty");
  write_colmap_text(dir3 + "/sparse/0", m);
  CHECK_THAT(error_of([&] { colmap_sequence(dir3, "x", ColmapSceneLayout{}); }),
             Catch::Contains("no images (empty sequence)"));
}

TEST_CASE("nerfstudio: transforms.json with applied_transform and 16-bit depth is consistent", "[data][nerfstudio]") {
  const auto g = test::make_tiny_dataset("ns_seq");
  const Sequence seq = nerfstudio_sequence(ns_scene(g), "atrium");
  REQUIRE(seq.frames.size() == 8);
  CHECK(seq.frames[0].depth == DepthSource::Png16Millimetres);
  const LoadedFrame a = load_frame(seq, 1), b = load_frame(seq, 3);
  const auto c = test::depth_consistency(a, b, 0.01, 1);
  INFO("checked " << c.checked << " agree " << c.agree << " median " << c.median_rel);
  CHECK(c.checked > 200);
  CHECK(c.agree > 0.85);
  CHECK(c.median_rel < 2e-3);  // millimetre quantization
}

TEST_CASE("nerfstudio: per-frame intrinsics, resized image folders and bad files", "[data][nerfstudio]") {
  const auto g = test::make_tiny_dataset("ns_variants");
  const std::string scene = ns_scene(g);
  auto j = nlohmann::json::parse(test::read_bytes(scene + "/transforms.json"));
  // The file declares a 128x96 camera while the images are 64x48: a resized copy, as in images_2/.
  j["w"] = 128;
  j["h"] = 96;
  j["fl_x"] = j["fl_x"].get<double>() * 2;
  j["fl_y"] = j["fl_y"].get<double>() * 2;
  j["cx"] = j["cx"].get<double>() * 2;
  j["cy"] = j["cy"].get<double>() * 2;
  j["frames"][0]["fl_x"] = 500.0;  // per-frame override
  test::write_bytes(scene + "/transforms.json", j.dump());
  const Sequence seq = nerfstudio_sequence(scene, "atrium");
  CHECK(seq.frames[0].view.intr.fx == 500.0);
  const LoadedFrame f = load_frame(seq, 1);
  CHECK(f.view.intr.width == 64);
  CHECK(f.view.intr.cx == Approx(32.0));
  j["frames"][2].erase("transform_matrix");
  test::write_bytes(scene + "/transforms.json", j.dump());
  CHECK_THAT(error_of([&] { nerfstudio_sequence(scene, "x"); }), Catch::Contains("missing 'transform_matrix'"));
  j["frames"] = nlohmann::json::array();
  test::write_bytes(scene + "/transforms.json", j.dump());
  CHECK_THAT(error_of([&] { nerfstudio_sequence(scene, "x"); }), Catch::Contains("empty sequence"));
  test::write_bytes(scene + "/transforms.json", "{oops");
  CHECK_THAT(error_of([&] { nerfstudio_sequence(scene, "x"); }), Catch::Contains("invalid JSON"));
}
