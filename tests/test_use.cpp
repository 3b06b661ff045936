// Using a checkpoint: EXIF focal lengths, camera paths, and the predict -> PLY -> render -> video path
// through the `infinisplat` tool itself.
#include <catch2/catch.hpp>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include <filesystem>
#include <sstream>

#include "core/error.h"
#include "core/log.h"
#include "geometry/trajectory.h"
#include "io/exif.h"
#include "io/ply.h"
#include "support/test_util.h"
#include "support/tiny_dataset.h"
#include "support/tiny_model.h"
#include "train/trainer.h"

using namespace isplat;
namespace fs = std::filesystem;

namespace {
// A minimal JPEG header with an APP1 Exif segment holding FocalLengthIn35mmFilm and FocalLength.
std::string exif_jpeg(bool little_endian, uint16_t f35, uint32_t num, uint32_t den) {
  std::string t;
  auto u16 = [&](uint16_t v) {
    if (little_endian)
      t += char(v & 0xFF), t += char(v >> 8);
    else
      t += char(v >> 8), t += char(v & 0xFF);
  };
  auto u32 = [&](uint32_t v) {
    if (little_endian)
      for (int i = 0; i < 4; ++i) t += char((v >> (8 * i)) & 0xFF);
    else
      for (int i = 3; i >= 0; --i) t += char((v >> (8 * i)) & 0xFF);
  };
  t += little_endian ? "II" : "MM";
  u16(42);
  u32(8);                                // IFD0 at 8
  u16(1);                                // one entry: ExifIFD pointer
  u16(0x8769), u16(4), u32(1), u32(26);  // Exif IFD at 26
  u32(0);
  u16(2);  // Exif IFD: two entries
  u16(0xA405), u16(3), u32(1), u16(f35), u16(0);
  u16(0x920A), u16(5), u32(1), u32(56);  // rational at 56
  u32(0);
  u32(num), u32(den);
  std::string app1 = std::string("Exif\0\0", 6) + t;
  std::string jpeg = "\xFF\xD8\xFF\xE1";
  const size_t len = app1.size() + 2;
  jpeg += char(len >> 8), jpeg += char(len & 0xFF);
  return jpeg + app1 + "\xFF\xDA";
}
}  // namespace

TEST_CASE("exif: 35 mm-equivalent and physical focal lengths, both byte orders", "[use]") {
  for (bool le : {true, false}) {
    const ExifFocal f = read_exif_focal(exif_jpeg(le, 28, 47, 10));
    REQUIRE(f.focal_35mm);
    CHECK(*f.focal_35mm == 28.0);
    REQUIRE(f.focal_mm);
    CHECK(*f.focal_mm == Approx(4.7));
  }
  CHECK(fx_from_35mm(36.0, 4000, 3000) == Approx(4000.0));
  CHECK_FALSE(read_exif_focal("not a jpeg").focal_35mm);
  CHECK_FALSE(read_exif_focal(std::string("\xFF\xD8\xFF\xE1\x00\x04xx", 8)).focal_35mm);  // truncated: no crash
}

TEST_CASE("trajectory: orbit, dolly and camera-path files", "[use]") {
  const View base{Intrinsics::from_hfov(1.0, 64, 48), Pose::Identity()};
  const auto orbit = orbit_path(base, 4.0, 8);
  REQUIRE(orbit.views.size() == 8);
  CHECK((orbit.views[0].T_cw - base.T_cw).norm() < 1e-9);  // starts at the source view
  for (const auto& v : orbit.views) {
    Eigen::Vector2d uv;
    double z = 0;
    REQUIRE(v.project(Eigen::Vector3d(0, 0, 4.0), uv, z));  // always looks at the point 4 m ahead
    CHECK(uv.x() == Approx(32.0).margin(1e-6));
    CHECK(uv.y() == Approx(24.0).margin(1e-6));
  }
  const auto dolly = dolly_path(base, 4.0, 4);
  CHECK(camera_center(dolly.views[1].T_cw).z() == Approx(1.2));  // 0.3 x depth forward
  const auto dir = test::temp_dir("traj");
  test::write_bytes(dir + "/p.json", R"({"frames": [{"T_cw": [[1,0,0,0.5],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}]})");
  const auto file = load_camera_path(dir + "/p.json", base);
  CHECK(camera_center(file.views[0].T_cw).x() == Approx(-0.5));
  test::write_bytes(dir + "/ns.json", R"({"render_width": 32, "render_height": 24, "camera_path": [
      {"camera_to_world": [1,0,0,0, 0,1,0,0, 0,0,1,2, 0,0,0,1], "fov": 90}]})");
  const auto ns = load_camera_path(dir + "/ns.json", base);
  CHECK(ns.views[0].intr.width == 32);
  CHECK(ns.views[0].intr.fy == Approx(12.0));
  CHECK(camera_center(ns.views[0].T_cw).z() == Approx(2.0));
  test::write_bytes(dir + "/bad.json", R"({"frames": [{"T_cw": [[1,0,0]]}]})");
  CHECK_THROWS_WITH(load_camera_path(dir + "/bad.json", base), Catch::Contains("frames[0].T_cw must have 4 rows"));
}

TEST_CASE("use: predict writes a PLY that render turns into frames and a video", "[use]") {
  test::QuietLogs quiet;
  const auto data = test::make_tiny_dataset("use_e2e", 8);
  const std::string run = test::temp_dir("use_run");
  TrainConfig c = test::tiny_train_config(data, run, 1);
  c.data.tuples.targets = 1;
  c.model.sampler.budget = 2000;
  Trainer t(c);
  t.train_step();
  t.save(run + "/ck.safetensors");
  const std::string scene = generated_eval_root(data.out, "courtyard_colmap") + "/scene_0";
  const std::string tool = (fs::path(ISPLAT_BINARY_DIR) / "infinisplat").string();
  const std::string out = test::temp_dir("use_out");
  // One photo with its depth; each run below adds its own flags.
  const std::string predict_photo = tool + " predict --checkpoint " + run + "/ck.safetensors --image " + scene +
                                    "/images/IMG_0002.jpg --depth " + scene + "/depth/IMG_0002.exr --hfov 65 ";
  const std::string predict = predict_photo + "--out " + out + "/scene.ply > " + out + "/predict.txt 2>&1";
  REQUIRE(std::system(predict.c_str()) == 0);
  const std::string report = test::read_bytes(out + "/predict.txt");
  CHECK_THAT(report, Catch::Contains("supports     2000"));
  CHECK_THAT(report, Catch::Contains("time (ms)"));
  {  // the time line: each stage, their sum, and the total with loading and writing, which is no smaller
    const size_t at = report.find("time (ms)");
    REQUIRE(at != std::string::npos);
    const std::string line = report.substr(at, report.find('\n', at) - at);
    std::istringstream words(line.substr(line.find("prior")));
    std::string key;
    double value = 0, sum = 0;
    while (words >> key && key != "|" && words >> value) sum += value;
    REQUIRE(line.find("| stages ") != std::string::npos);
    REQUIRE(line.find("| total with loading and writing ") != std::string::npos);
    const double stages = std::stod(line.substr(line.find("| stages ") + 9));
    const double total = std::stod(line.substr(line.find("loading and writing ") + 20));
    CHECK(stages > 0);
    CHECK(std::abs(stages - sum) <= 3.5);  // six values, each rounded to whole ms
    CHECK(total >= stages - 1);
  }
  const Gaussians g = read_ply(out + "/scene.ply");
  CHECK(g.count() > 1000);
  CHECK(fs::exists(out + "/scene.camera.json"));
  // The PLY's header says what pruning removed, in the printed line's counts.
  auto pruning_comment = [](const std::string& ply) {
    for (const std::string& c : read_ply_comments(ply))
      if (c.rfind("pruning: ", 0) == 0) return c;
    return std::string();
  };
  CHECK_THAT(pruning_comment(out + "/scene.ply"), Catch::EndsWith(", kept " + std::to_string(g.count())));
  // The PLY records the size it was predicted at, and predict reports what a viewer at 4x that size sees through the
  // surface; --photo-size predicts at the photo's own size (here already a multiple of 16).
  auto size_comment = [](const std::string& ply) {
    for (const std::string& c : read_ply_comments(ply))
      if (c.rfind("working_size ", 0) == 0) return c;
    return std::string();
  };
  CHECK_THAT(size_comment(out + "/scene.ply"), Catch::EndsWith(" (photo 64x48)"));
  CHECK_THAT(report, Catch::Contains("of the source view's centre shows gaps at 4x the working size"));
  const std::string full_size = predict_photo + "--photo-size --out " + out + "/full.ply > " + out + "/full.txt 2>&1";
  REQUIRE(std::system(full_size.c_str()) == 0);
  CHECK(size_comment(out + "/full.ply") == "working_size 64x48 (photo 64x48)");
  CHECK_THAT(test::read_bytes(out + "/full.txt"), Catch::Contains("working size 64x48"));
  // The written Gaussians get the viewer's floor (--view-floor, default 0.45 px) unless the checkpoint's is larger;
  // --view-floor 0 writes the checkpoint's own: the same Gaussians, none wider, most narrower.
  auto floor_comment = [](const std::string& ply) {
    for (const std::string& c : read_ply_comments(ply))
      if (c.rfind("scale_floor_px ", 0) == 0) return c;
    return std::string();
  };
  CHECK_THAT(floor_comment(out + "/scene.ply"), Catch::StartsWith("scale_floor_px 0.45 (the checkpoint's: "));
  const std::string own_floor = predict_photo + "--view-floor 0 --out " + out + "/own_floor.ply > /dev/null 2>&1";
  REQUIRE(std::system(own_floor.c_str()) == 0);
  const std::string own = floor_comment(out + "/own_floor.ply");
  const std::string own_value = own.substr(15, own.find(' ', 15) - 15);
  CHECK(own == "scale_floor_px " + own_value + " (the checkpoint's: " + own_value + ")");
  const Gaussians narrow = read_ply(out + "/own_floor.ply");
  REQUIRE(narrow.count() == g.count());
  const auto widened = g.scales - narrow.scales;  // same supports, same order
  CHECK(widened.min().item<float>() >= -1e-6f);
  CHECK((widened > 1e-6f).to(torch::kFloat32).mean().item<float>() > 0.5f);
  // Pruning by contribution drops what stays faint over the source and 2 nearby views; the printed count, the PLY's
  // comment and the Gaussians written agree (the run is the same as above up to that rule).
  const std::string prune = predict_photo + "--prune-contribution 0.05 --prune-views 2 --out " + out +
                            "/pruned.ply > " + out + "/pruned.txt 2>&1";
  REQUIRE(std::system(prune.c_str()) == 0);
  const int64_t faint = g.count() - read_ply(out + "/pruned.ply").count();
  CHECK(faint > 0);
  CHECK_THAT(test::read_bytes(out + "/pruned.txt"),
             Catch::Contains(std::to_string(faint) + " below contribution 0.05 over the source and 2 nearby views"));
  CHECK_THAT(pruning_comment(out + "/pruned.ply"),
             Catch::Contains("low_contribution " + std::to_string(faint) + " (min_contribution 0.05, views 2)") &&
                 Catch::EndsWith(", kept " + std::to_string(g.count() - faint)));
  // Merging writes fewer Gaussians and says how many it merged (an untrained model's Gaussians have random
  // shapes, hence any shape is allowed).
  const std::string merge = predict_photo + "--merge-cell 4 --merge-color 1 --merge-flatness 1 --merge-normal-cos 0 " +
                            "--out " + out + "/merged.ply > " + out + "/merged.txt 2>&1";
  REQUIRE(std::system(merge.c_str()) == 0);
  const Gaussians merged = read_ply(out + "/merged.ply");
  CHECK(merged.count() < g.count());
  const std::string merge_report = test::read_bytes(out + "/merged.txt");
  CHECK_THAT(merge_report, Catch::Contains("Gaussians    " + std::to_string(merged.count()) + " written of " +
                                           std::to_string(g.count()) + " decoded"));
  CHECK_THAT(merge_report, Catch::Contains(std::to_string(g.count() - merged.count()) + " merged into neighbours"));
  CHECK_THAT(merge_report, Catch::Contains("groups refused:"));
  // A merge flag outside the schema's bounds fails, naming the key.
  const std::string bad_merge = predict_photo + "--merge-cell 4 --merge-flatness 2 --out " + out + "/bad_merge.ply > " +
                                out + "/bad_merge.txt 2>&1";
  CHECK(std::system(bad_merge.c_str()) != 0);
  CHECK_THAT(test::read_bytes(out + "/bad_merge.txt"), Catch::Contains("max_flatness"));
  CHECK_FALSE(fs::exists(out + "/bad_merge.ply"));
  // --fill-holes gives the photo's invalid depth (its sky, near the skyline) supports, so the scene changes; a
  // negative distance fails, naming the key.
  const std::string fill = predict_photo + "--fill-holes 8 --out " + out + "/filled.ply > " + out + "/filled.txt 2>&1";
  REQUIRE(std::system(fill.c_str()) == 0);
  const Gaussians filled = read_ply(out + "/filled.ply");
  CHECK(filled.count() == g.count());  // the same budget, placed over more of the photo
  CHECK_FALSE(torch::equal(filled.means, g.means));
  // --align-points scales the scene about the camera by the median ratio of the points' z to the predicted depth:
  // points twice as far give a scene twice as large, and the PLY and the printout say by how much.
  for (const auto& [name, z] : {std::pair{"near", 5.0}, {"far", 10.0}}) {
    std::string csv = "u,v,z\n";
    for (int k = 0; k < 9; ++k) csv += cat(20 + 3 * k, ",", 18 + k, ",", z, "\n");
    test::write_bytes(out + "/" + name + ".csv", csv);
    const std::string aligned = predict_photo + "--align-points " + out + "/" + name + ".csv --out " + out + "/" +
                                name + ".ply > " + out + "/" + name + ".txt 2>&1";
    REQUIRE(std::system(aligned.c_str()) == 0);
    CHECK_THAT(test::read_bytes(out + "/" + name + ".txt"), Catch::Contains("scale        x"));
  }
  const Gaussians near = read_ply(out + "/near.ply"), far = read_ply(out + "/far.ply");
  REQUIRE(near.count() == far.count());
  CHECK(torch::allclose(far.means, 2 * near.means, 1e-4, 1e-5));
  CHECK(torch::allclose(far.scales, 2 * near.scales, 1e-4, 1e-6));
  bool commented = false;
  for (const std::string& c : read_ply_comments(out + "/far.ply")) commented |= c.rfind("scale_aligned ", 0) == 0;
  CHECK(commented);
  const std::string bad_fill =
      predict_photo + "--fill-holes -3 --out " + out + "/bad_fill.ply > " + out + "/bad_fill.txt 2>&1";
  CHECK(std::system(bad_fill.c_str()) != 0);
  CHECK_THAT(test::read_bytes(out + "/bad_fill.txt"), Catch::Contains("fill_px"));
  const std::string render = tool + " render --ply " + out +
                             "/scene.ply --trajectory orbit --frames 5 --depth --normal --out " + out + "/orbit > " +
                             out + "/render.txt 2>&1";
  REQUIRE(std::system(render.c_str()) == 0);
  for (const char* f : {"frame_0000.png", "frame_0004.png", "depth_0002.png", "normal_0003.png"})
    CHECK(fs::exists(fs::path(out) / "orbit" / f));
  cv::VideoCapture video(out + "/orbit/video.mp4");
  REQUIRE(video.isOpened());
  CHECK(static_cast<int>(video.get(cv::CAP_PROP_FRAME_COUNT)) == 5);
  // The side-by-side strip: RGB | depth | normals | alpha, four frames wide, and the video shows it.
  const std::string strip = tool + " render --ply " + out + "/scene.ply --trajectory dolly --frames 3 --strip --out " +
                            out + "/strip > " + out + "/strip.txt 2>&1";
  REQUIRE(std::system(strip.c_str()) == 0);
  const cv::Mat frame = cv::imread(out + "/orbit/frame_0000.png"), s0 = cv::imread(out + "/strip/strip_0000.png");
  REQUIRE(!s0.empty());
  CHECK(s0.cols == 4 * frame.cols);
  CHECK(s0.rows == frame.rows);
  cv::VideoCapture strip_video(out + "/strip/video.mp4");
  REQUIRE(strip_video.isOpened());
  CHECK(static_cast<int>(strip_video.get(cv::CAP_PROP_FRAME_WIDTH)) == 4 * frame.cols);
  // Bad input is named.
  const std::string bad = tool + " predict --checkpoint " + run + "/ck.safetensors --image " + out +
                          "/none.jpg --out " + out + "/x.ply > " + out + "/bad.txt 2>&1";
  CHECK(std::system(bad.c_str()) != 0);
  CHECK_THAT(test::read_bytes(out + "/bad.txt"), Catch::Contains("none.jpg: no such file"));
}
