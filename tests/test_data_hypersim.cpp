// Hypersim reader on generated data: layout, skips with counts, poses and depth consistent across views
// (including a tilt-shift camera), HDR colour path, NaN depth masking and malformed metadata.
#include <catch2/catch.hpp>

#include <filesystem>

#include "core/error.h"
#include "data/hypersim.h"
#include "data/synth/builder.h"
#include "io/csv.h"
#include "io/hdf5_io.h"
#include "support/consistency.h"
#include "support/test_util.h"
#include "support/tiny_dataset.h"

using namespace isplat;
namespace fs = std::filesystem;

namespace {
HypersimOptions reader_options(const GenerateOptions& g, const std::string& split) {
  HypersimOptions h;
  h.root = generated_hypersim_root(g.out);
  h.split = split;
  return h;
}

// Two scenes of one style, generated and read back through the reader: each first frame has valid, finite depth.
HypersimIndex written_and_read_back(const std::string& style, int frames) {
  test::QuietLogs quiet;
  const auto g = test::style_dataset_options(test::temp_dir("hs_" + style), frames, {style}, 2);
  generate_datasets(g);
  HypersimIndex index = read_hypersim(reader_options(g, "train"));
  REQUIRE(index.sequences.size() == 2);
  for (const Sequence& seq : index.sequences) {
    const LoadedFrame fr = load_frame(seq, 0);
    REQUIRE(fr.has_depth());
    CHECK(cv::countNonZero(fr.depth.valid) > 0);
    CHECK(cv::checkRange(fr.depth.depth));
  }
  return index;
}
}  // namespace

TEST_CASE("hypersim: the reader finds the generated split and counts what it skips", "[data][hypersim]") {
  const auto g = test::make_tiny_dataset("hs_index");
  const auto train = read_hypersim(reader_options(g, "train"));
  REQUIRE(train.sequences.size() == 1);
  CHECK(train.sequences[0].scene == "ai_001_001");
  CHECK(train.frames == 7);  // frame 5 is flagged, has no split and no files
  CHECK(train.skipped.at("frames of scenes without files (no _detail/metadata_scene.csv)") == 3);  // ai_099_001
  CHECK(read_hypersim(reader_options(g, "all")).skipped.at("frames not in the public release") == 1);
  const auto val = read_hypersim(reader_options(g, "val"));
  REQUIRE(val.sequences.size() == 1);
  CHECK(val.sequences[0].hypersim->tilt_shift);
  CHECK(val.frames == 8);
  auto opts = reader_options(g, "all");
  opts.scene_blacklist = {"ai_001_001"};
  const auto all = read_hypersim(opts);
  CHECK(all.sequences.size() == 1);
  CHECK(all.skipped.at("frames in blacklisted scenes") == 8);
  CHECK_THAT(all.summary(), Catch::Contains("blacklisted"));
}

TEST_CASE("hypersim: depth and poses agree across views, with and without tilt-shift", "[data][hypersim]") {
  const auto g = test::make_tiny_dataset("hs_consistency");
  for (const std::string split : {"train", "val"}) {
    const auto index = read_hypersim(reader_options(g, split));
    const Sequence& seq = index.sequences.at(0);
    const LoadedFrame a = load_frame(seq, 0), b = load_frame(seq, 3);
    REQUIRE(a.has_depth());
    CHECK(a.image.cols == 64);
    const auto c = test::depth_consistency(a, b, 0.02, 1);
    INFO(split << ": checked " << c.checked << ", agree " << c.agree << ", median " << c.median_rel);
    CHECK(c.checked > 200);
    CHECK(c.agree > 0.9);         // the rest are occlusions
    CHECK(c.median_rel < 0.002);  // float16 depth is good to ~0.05 %
  }
}

TEST_CASE("hypersim: NaN depth (windows) comes back masked", "[data][hypersim]") {
  auto g = test::tiny_dataset_options(test::temp_dir("hs_nan"), 8);
  g.eval_datasets.clear();
  generate_datasets(g);
  int64_t invalid = 0;
  const auto index = read_hypersim(reader_options(g, "all"));
  for (const auto& seq : index.sequences)
    for (size_t i = 0; i < seq.frames.size(); ++i) {
      const auto f = load_frame(seq, i);
      invalid += f.depth.invalid_count;
      CHECK(cv::checkRange(f.depth.depth));
    }
  CHECK(invalid > 0);  // rooms have windows onto the sky, as Hypersim has NaN where there is no geometry
}

TEST_CASE("hypersim: the HDR colour path applies the official tone map", "[data][hypersim]") {
  const auto g = test::make_tiny_dataset("hs_hdf5");
  auto opts = reader_options(g, "val");
  const auto jpg = read_hypersim(opts);
  opts.color = "hdf5";
  const auto hdr = read_hypersim(opts);
  // Frame 0 sets the generator's per-scene exposure, so the per-image tone map gives the same image.
  const cv::Mat a = load_frame(jpg.sequences[0], 0, false).image, b = load_frame(hdr.sequences[0], 0, false).image;
  CHECK(cv::norm(a, b, cv::NORM_L1) / (a.total() * 3) < 0.02);
  cv::Mat flat(4, 4, CV_32FC3, cv::Scalar(0.5, 0.5, 0.5));
  const cv::Mat t = hypersim_tonemap(flat);
  CHECK(t.at<cv::Vec3f>(0, 0)[0] == Approx(0.8f).margin(1e-5));  // the 90th percentile maps to 0.8
}

TEST_CASE("hypersim: missing files are skipped and malformed metadata names the file", "[data][hypersim]") {
  const auto g = test::make_tiny_dataset("hs_bad");
  const std::string root = generated_hypersim_root(g.out);
  fs::remove(fs::path(root) / "ai_001_001/images/scene_cam_00_geometry_hdf5/frame.0002.depth_meters.hdf5");
  const auto index = read_hypersim(reader_options(g, "train"));
  CHECK(index.frames == 6);
  CHECK(index.skipped.at("frames with missing image or depth files") == 1);

  // Orientation dataset of the wrong shape.
  const std::string opath = (fs::path(root) / "ai_001_001/_detail/cam_00/camera_keyframe_orientations.hdf5").string();
  std::vector<double> junk(8 * 4, 0.0);
  write_hdf5(opath, {8, 4}, junk.data(), H5Type::Float64, 0);
  CHECK_THROWS_WITH(read_hypersim(reader_options(g, "train")),
                    Catch::Contains("camera_keyframe_orientations.hdf5: expected shape [N, 3, 3]"));
  // Camera CSV lacking a column.
  CsvTable cams = read_csv((fs::path(root) / "metadata_camera_parameters.csv").string());
  cams.header[5] = "renamed";
  write_csv((fs::path(root) / "metadata_camera_parameters.csv").string(), cams);
  CHECK_THROWS_WITH(read_hypersim(reader_options(g, "train")), Catch::Contains("missing column 'M_cam_from_uv_00'"));
  HypersimOptions nowhere;
  nowhere.root = g.out + "/nope";
  CHECK_THROWS_WITH(read_hypersim(nowhere), Catch::Contains("data.hypersim.root"));
}

TEST_CASE("hypersim: desk, street and hall scenes with varied fields of view read back through the reader",
          "[data][hypersim]") {
  test::QuietLogs quiet;
  auto g = test::style_dataset_options(test::temp_dir("hs_styles"), 8, {"desk", "street", "hall"}, 3);
  g.hfov_deg = {40, 90};
  generate_datasets(g);
  const auto index = read_hypersim(reader_options(g, "train"));
  REQUIRE(index.sequences.size() == 3);
  double max_depth[3] = {0, 0, 0};
  std::vector<double> fx;
  for (size_t s = 0; s < 3; ++s) {
    const Sequence& seq = index.sequences[s];
    fx.push_back(seq.frames.at(0).view.intr.fx);
    for (size_t f = 0; f < seq.frames.size(); f += 2) {
      const LoadedFrame fr = load_frame(seq, f);
      REQUIRE(fr.has_depth());
      double lo = 0, hi = 0;
      cv::minMaxLoc(fr.depth.depth, &lo, &hi, nullptr, nullptr, fr.depth.valid);
      max_depth[s] = std::max(max_depth[s], hi);
    }
  }
  CHECK(max_depth[0] < 4.0);                    // a tabletop close-up
  CHECK(max_depth[1] > 25.0);                   // a street runs far
  CHECK(max_depth[2] > 10.0);                   // a hall is larger than any room (at most 11 m deep) ...
  CHECK(max_depth[2] < 50.0);                   // ... and closed
  CHECK(fx[0] != Approx(fx[1]).epsilon(0.01));  // fields of view differ per scene
  // Depth agrees across views for the new styles too.
  const auto c = test::depth_consistency(load_frame(index.sequences[0], 0), load_frame(index.sequences[0], 2), 0.02, 1);
  CHECK(c.agree > 0.8);
}

TEST_CASE("hypersim: clutter scenes span scales from a desk to a street and read back through the reader",
          "[data][hypersim]") {
  // The builder: deterministic per seed, and its scene scale (the ground's width, 12 x scale) varies widely.
  double smallest = 1e9, largest = 0;
  for (uint64_t seed = 0; seed < 200; ++seed) {
    const synth::Scene s = synth::build_clutter(seed);
    CHECK(s.style == "clutter");
    CHECK(s.prims.size() >= 26);  // the ground and at least 25 objects
    const double width = s.prims.at(0).e1.norm();
    smallest = std::min(smallest, width), largest = std::max(largest, width);
    int in_walk_box = 0, low_ceilings = 0;  // no object reaches back over the cameras; no ceiling sits on them
    for (const synth::Primitive& p : s.prims) {
      if (p.shape != synth::Shape::Quad) in_walk_box += p.bmin.y() < s.walk_max.y();
      const bool ceiling = p.shape == synth::Shape::Quad && p.e1.z() == 0 && p.e2.z() == 0 && p.p0.z() > 0;
      low_ceilings += ceiling && p.p0.z() < s.walk_max.z() + 0.5;
    }
    CHECK(in_walk_box == 0);
    CHECK(low_ceilings == 0);
  }
  CHECK(smallest < 12.0 * 0.8);  // scale below 0.8: desk-sized
  CHECK(largest > 12.0 * 3.0);   // scale above 3: street-sized
  CHECK(synth::build_clutter(7).prims.at(9).p0 == synth::build_clutter(7).prims.at(9).p0);
  // The generator writes them in the release layout; depth is valid, finite and agrees across views.
  const HypersimIndex index = written_and_read_back("clutter", 6);
  const auto c = test::depth_consistency(load_frame(index.sequences[0], 0), load_frame(index.sequences[0], 2), 0.02, 1);
  CHECK(c.agree > 0.8);
}
