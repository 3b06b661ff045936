// Hostile and damaged input for every reader family (issue 15): each ends in an Error naming the file,
// never a crash, a hang, an exhausted memory or silently wrong data; training state survives damage.
#include <catch2/catch.hpp>

#include <sys/wait.h>
#include <torch/torch.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <opencv2/core.hpp>

#include "core/config.h"
#include "core/error.h"
#include "core/paths.h"
#include "core/runtime.h"
#include "data/colmap.h"
#include "data/nerfstudio.h"
#include "eval/evaluator.h"
#include "eval/pairs.h"
#include "eval/results_log.h"
#include "geometry/trajectory.h"
#include "io/atomic_file.h"
#include "io/checkpoint.h"
#include "io/csv.h"
#include "io/folder_lock.h"
#include "io/hdf5_io.h"
#include "io/image_io.h"
#include "io/jsonl.h"
#include "io/ply.h"
#include "io/safetensors.h"
#include "model/model_io.h"
#include "prior/learned_depth.h"
#include "support/test_util.h"
#include "support/tiny_dataset.h"
#include "support/tiny_model.h"
#include "train/train_config.h"
#include "train/trainer.h"

using namespace isplat;
using test::error_of;
namespace fs = std::filesystem;

namespace {

// The checkpoint of a tiny model trained for one step (dataset depth, so no prior is embedded).
Checkpoint one_step_checkpoint(const std::string& tag) {
  const auto data = test::make_tiny_dataset(tag, 8);
  const std::string run = test::temp_dir(tag + "_run");
  {
    Trainer t(test::tiny_train_config(data, run, 1));
    t.save(run + "/ck.safetensors");
  }
  return load_checkpoint(run + "/ck.safetensors");
}

// A safetensors file from a hand-written header (the writer never produces these).
void write_safetensors_raw(const std::string& path, const std::string& header, const std::string& data) {
  std::string bytes(8, '\0');
  for (int i = 0; i < 8; ++i) bytes[i] = static_cast<char>((header.size() >> (8 * i)) & 0xFF);
  test::write_bytes(path, bytes + header + data);
}

// Replaces every occurrence of `from` in the file by `to` (same length); returns how many.
int patch_bytes(const std::string& path, const std::string& from, const std::string& to) {
  std::string bytes = test::read_bytes(path);
  int n = 0;
  for (size_t at = bytes.find(from); at != std::string::npos; at = bytes.find(from, at + to.size()), ++n)
    bytes.replace(at, from.size(), to);
  test::write_bytes(path, bytes);
  return n;
}

std::string u64le(uint64_t v) {
  std::string s(8, '\0');
  for (int i = 0; i < 8; ++i) s[i] = static_cast<char>((v >> (8 * i)) & 0xFF);
  return s;
}

Checkpoint resumable_checkpoint(int64_t step) {
  Checkpoint ck;
  ck.tensors["model/w"] = torch::full({4}, static_cast<float>(step));
  ck.tensors["optim/state"] = bytes_to_tensor("opt");
  ck.tensors["rng/torch"] = torch::zeros({8}, torch::kUInt8);
  ck.metadata["step"] = std::to_string(step);
  return ck;
}

cv::Mat gradient(int h, int w) {
  cv::Mat img(h, w, CV_32FC3);
  for (int i = 0; i < h; ++i)
    for (int j = 0; j < w; ++j) img.at<cv::Vec3f>(i, j) = cv::Vec3f(j / float(w), i / float(h), (i * j % 17) / 17.0f);
  return img;
}

}  // namespace

TEST_CASE("reliability: JSON readers refuse deep nesting, huge numbers, folders and wrong types by name",
          "[reliability][json]") {
  const std::string dir = test::temp_dir("rel_json");
  const std::string deep = dir + "/deep.json";
  test::write_bytes(deep, std::string(200000, '[') + std::string(200000, ']'));
  CHECK_THAT(error_of([&] { read_json_file(deep); }), Catch::Contains(deep) && Catch::Contains("nested deeper"));
  const std::string huge = dir + "/huge.json";
  test::write_bytes(huge, R"({"runtime": {"seed": 1e400}})");
  CHECK_THAT(error_of([&] { merge_config(huge, {}); }), Catch::Contains(huge) && Catch::Contains("invalid JSON"));
  const std::string based = dir + "/based.json";
  fs::create_directories(dir + "/folder");
  test::write_bytes(based, R"({"base": "folder"})");
  CHECK_THAT(error_of([&] { merge_config(based, {}); }), Catch::Contains("is a folder"));
  // A wrong type in a guarded reader names the file instead of escaping as an nlohmann exception.
  const nlohmann::json j = {{"K", "not a matrix"}};
  CHECK_THAT(error_of([&] { guard_json("cam.json", [&] { return j.at("K").at(0).get<double>(); }); }),
             Catch::Contains("cam.json: malformed content"));

  // Camera paths: a huge output size and short rows are refused before anything is allocated.
  const View base{Intrinsics{50, 50, 32, 24, 64, 48}, Pose::Identity()};
  const std::string cam = dir + "/path.json";
  test::write_bytes(
      cam, R"({"width": 100000, "height": 100000, "frames": [{"T_cw": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}]})");
  CHECK_THAT(error_of([&] { load_camera_path(cam, base); }),
             Catch::Contains(cam) && Catch::Contains("not a usable image size"));
  test::write_bytes(cam, R"({"frames": [{"T_cw": [[1,0,0,0],[0,1],[0,0,1,0],[0,0,0,1]]}]})");
  CHECK_THAT(error_of([&] { load_camera_path(cam, base); }), Catch::Contains("frames[0].T_cw row 1 must hold 4"));
  test::write_bytes(cam, R"({"frames": [{"T_cw": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]], "K": [[1,0],[0,1]]}]})");
  CHECK_THAT(error_of([&] { load_camera_path(cam, base); }), Catch::Contains("frames[0].K must have 3 rows"));

  // Manifests: a number beyond double and a bin the manifest does not have.
  const std::string manifest = dir + "/manifest.json";
  test::write_bytes(manifest, R"({"dataset": "x", "pairs": [{"baseline": 1e309}]})");
  CHECK_THAT(error_of([&] { read_manifest(manifest); }), Catch::Contains(manifest) && Catch::Contains("invalid JSON"));
}

TEST_CASE("reliability: configs that used to pass validation and fail later are refused up front",
          "[reliability][config]") {
  CHECK_THAT(error_of([] { load_config<TrainConfig>("", {"loss.scale_bounds=[]"}); }),
             Catch::Contains("loss.scale_bounds") && Catch::Contains("two increasing numbers"));
  CHECK_THAT(error_of([] { load_config<TrainConfig>("", {"loss.scale_bounds=[-3, -8]"}); }),
             Catch::Contains("loss.scale_bounds"));
  CHECK_THAT(error_of([] { load_config<TrainConfig>("", {"runtime.threads=100000"}); }),
             Catch::Contains("runtime.threads"));
  CHECK_THAT(error_of([] { load_config<TrainConfig>("", {"model.sampler.budget=2e7"}); }),
             Catch::Contains("model.sampler.budget"));
  CHECK_THAT(error_of([] { load_config<TrainConfig>("", {"model.encoder.vit.embed_dim=100000"}); }),
             Catch::Contains("model.encoder.vit.embed_dim"));
  CHECK_THAT(error_of([] { configure_threads(100000); }), Catch::Contains("threads"));
  CHECK(load_config<TrainConfig>("", {}).loss.scale_bounds.size() == 2);  // the defaults still pass
}

TEST_CASE("reliability: HDF5 with an empty extent or 2^36 declared elements is refused before allocating",
          "[reliability][hdf5]") {
  const std::string dir = test::temp_dir("rel_hdf5");
  const std::string empty = dir + "/empty.hdf5";
  const std::vector<float> none;
  write_hdf5(empty, {0, 4}, none.data(), H5Type::Float32, 0);
  CHECK_THAT(error_of([&] { read_hdf5_float(empty); }), Catch::Contains(empty) && Catch::Contains("is empty"));
  // Declared dimensions patched in the dataspace message: 3 x 2^34 elements, no data behind them.
  const std::string huge = dir + "/huge.hdf5";
  const std::vector<float> v(3 * 5, 1.0f);
  write_hdf5(huge, {3, 5}, v.data(), H5Type::Float32, 0);
  REQUIRE(patch_bytes(huge, u64le(3) + u64le(5), u64le(3) + u64le(uint64_t{1} << 34)) >= 1);
  CHECK_THAT(error_of([&] { read_hdf5_float(huge); }), Catch::Contains(huge) && Catch::Contains("declares shape"));
}

TEST_CASE("reliability: a PLY declaring 2^62 vertices or holding NaN is a named error", "[reliability][ply]") {
  const std::string dir = test::temp_dir("rel_ply");
  Gaussians g;
  g.means = torch::rand({3, 3});
  g.colors = torch::rand({3, 3});
  g.opacities = torch::full({3}, 0.5);
  g.scales = torch::full({3, 3}, 0.1);
  g.quats = torch::tensor({1.0f, 0.0f, 0.0f, 0.0f}).repeat({3, 1});
  const std::string ply = dir + "/scene.ply";
  write_ply(ply, g);
  const std::string good = test::read_bytes(ply);
  REQUIRE(patch_bytes(ply, "element vertex 3\n", "element vertex 4611686018427387904\n") == 1);
  CHECK_THAT(error_of([&] { read_ply(ply); }), Catch::Contains(ply) && Catch::Contains("truncated"));
  std::string nan = good;
  const float q = std::numeric_limits<float>::quiet_NaN();
  nan.replace(nan.size() - 4, 4, reinterpret_cast<const char*>(&q), 4);  // the last vertex's rot_3
  test::write_bytes(ply, nan);
  CHECK_THAT(error_of([&] { read_ply(ply); }), Catch::Contains("vertex 2 property 'rot_3' is not finite"));
}

TEST_CASE("reliability: JPEG with corrupt scan data and images declaring 20000x20000 are refused",
          "[reliability][image]") {
  const std::string dir = test::temp_dir("rel_image");
  const std::string jpg = dir + "/photo.jpg";
  write_image(jpg, gradient(96, 128));
  CHECK(read_image(jpg).cols == 128);
  std::string bytes = test::read_bytes(jpg);
  const size_t sos = bytes.find("\xFF\xDA");
  REQUIRE(sos != std::string::npos);
  // Scan data overwritten between the start of scan and the end marker: libjpeg only warns about it.
  const size_t from = sos + 40, to = bytes.size() - 40;
  REQUIRE(from < to);
  for (size_t i = from; i < to; i += 7) bytes[i] = static_cast<char>(0xFF), bytes[i + 1] = static_cast<char>(0xD3);
  test::write_bytes(jpg, bytes);
  CHECK_THAT(error_of([&] { read_image(jpg); }), Catch::Contains(jpg) && Catch::Contains("corrupt JPEG"));

  const std::string big = dir + "/big.jpg";
  write_image(big, gradient(48, 64));
  // SOF0: FF C0, length (2), precision (1), height (2), width (2).
  REQUIRE(patch_bytes(big, std::string("\xFF\xC0\x00\x11\x08\x00\x30\x00\x40", 9),
                      std::string("\xFF\xC0\x00\x11\x08\x4E\x20\x4E\x20", 9)) == 1);
  CHECK_THAT(error_of([&] { read_image(big); }),
             Catch::Contains(big) && Catch::Contains("20000x20000") && Catch::Contains("max_image_pixels"));
  const std::string png = dir + "/big.png";
  write_image(png, gradient(48, 64));
  REQUIRE(patch_bytes(png, std::string("IHDR\x00\x00\x00\x40\x00\x00\x00\x30", 12),
                      std::string("IHDR\x00\x00\x4E\x20\x00\x00\x4E\x20", 12)) == 1);
  CHECK_THAT(error_of([&] { read_image(png); }), Catch::Contains(png) && Catch::Contains("max_image_pixels"));
}

TEST_CASE("reliability: safetensors shapes that overflow, and checkpoints with edited dtypes or flipped bits",
          "[reliability][safetensors]") {
  const std::string dir = test::temp_dir("rel_st");
  const std::string st = dir + "/t.safetensors";
  write_safetensors_raw(st, R"({"a":{"dtype":"F32","shape":[9223372036854775808],"data_offsets":[0,0]}})", "");
  CHECK_THAT(error_of([&] { read_safetensors(st); }), Catch::Contains(st) && Catch::Contains("bad dimension"));
  // 2^32 x 2^32 x 4 bytes wraps to 0 bytes in 64 bits.
  write_safetensors_raw(st, R"({"a":{"dtype":"F32","shape":[4294967296,4294967296],"data_offsets":[0,0]}})", "");
  CHECK_THAT(error_of([&] { read_safetensors(st); }), Catch::Contains("fit in 64 bits"));

  const std::string ck = dir + "/ck.safetensors";
  save_checkpoint(ck, resumable_checkpoint(3));
  CHECK(load_checkpoint(ck).step() == 3);
  const std::string good = test::read_bytes(ck);
  REQUIRE(patch_bytes(ck, "\"F32\"", "\"I32\"") == 1);  // same size, so only the checksum can tell
  CHECK_THAT(error_of([&] { load_checkpoint(ck); }), Catch::Contains(ck) && Catch::Contains("checksum mismatch"));
  std::string flipped = good;
  flipped[flipped.size() - 9] ^= 0x10;  // one bit of the data section
  test::write_bytes(ck, flipped);
  CHECK_THAT(error_of([&] { load_checkpoint(ck); }), Catch::Contains("checksum mismatch"));
  // Integers offered for float weights are a mismatch, not a silent conversion.
  torch::nn::Linear lin(2, 2);
  std::map<std::string, torch::Tensor> tensors = {{"m/weight", torch::zeros({2, 2}, torch::kInt32)},
                                                  {"m/bias", torch::zeros({2})}};
  CHECK_THAT(error_of([&] { load_named_tensors(*lin, tensors, "m/", "file.safetensors"); }),
             Catch::Contains("type mismatches") && Catch::Contains("weight"));
}

TEST_CASE("reliability: checkpoint folder keeps separate files, falls back to an intact one, cleans temporaries",
          "[reliability][checkpoint]") {
  test::QuietLogs quiet;
  const std::string dir = test::temp_dir("rel_ckfolder");
  CheckpointFolder folder(dir, 3);
  folder.save_periodic(1, resumable_checkpoint(1));
  folder.save_periodic(2, resumable_checkpoint(2));
  folder.alias("last", "best");
  CHECK(fs::hard_link_count(folder.path("last")) == 1);
  CHECK(fs::hard_link_count(folder.path("step_000002")) == 1);
  // Damage `last` in place: its twin step_000002 is unharmed and resume falls back to it.
  std::string bytes = test::read_bytes(folder.path("last"));
  bytes[bytes.size() - 3] ^= 0x01;
  test::write_bytes(folder.path("last"), bytes);
  auto found = folder.newest_intact();
  REQUIRE(found);
  CHECK(found->checkpoint.step() == 2);
  CHECK(found->path != folder.path("last"));
  fs::remove(folder.path("last"));
  fs::remove(folder.path("best"));
  fs::remove(folder.path("step_000002"));
  found = folder.newest_intact();
  REQUIRE(found);
  CHECK(found->path == folder.path("step_000001"));
  // A killed write's temporary (its writer's pid has ended) is removed; real checkpoints are not.
  const pid_t killed = ::fork();
  if (killed == 0) ::_exit(0);
  ::waitpid(killed, nullptr, 0);
  const std::string temporary = cat(dir, "/.last.isplat-tmp", killed, "_0.safetensors");
  test::write_bytes(temporary, "half");
  CHECK(folder.remove_stale_temporaries() == 1);
  CHECK(fs::exists(folder.path("step_000001")));
  CHECK_FALSE(fs::exists(temporary));
}

TEST_CASE("reliability: one trainer per run folder, unwritable folders and damaged state fail cleanly",
          "[reliability][train]") {
  test::QuietLogs quiet;
  const std::string dir = test::temp_dir("rel_lock");
  {
    FolderLock first(dir);
    CHECK_THAT(error_of([&] { FolderLock second(dir); }),
               Catch::Contains(dir) && Catch::Contains(cat("pid ", getpid())));
    // The evaluator refuses a checkpoint of a run that is still training, and only inside a run folder.
    CHECK(folder_lock_holder(dir) == std::to_string(getpid()));
    const std::string in_run = dir + "/checkpoints/last.safetensors";
    CHECK_THAT(error_of([&] { require_finished_run("full_s3", in_run); }),
               Catch::Contains("full_s3") && Catch::Contains(in_run) && Catch::Contains("still training") &&
                   Catch::Contains(cat("pid ", getpid())));
    CHECK_NOTHROW(require_finished_run("full_s3", dir + "/last.safetensors"));
  }
  CHECK(folder_lock_holder(dir).empty());  // released with its holder
  CHECK_NOTHROW(require_finished_run("full_s3", dir + "/checkpoints/last.safetensors"));
  CHECK(folder_lock_holder(test::temp_dir("rel_no_lock")).empty());  // no lock file at all
  FolderLock again(dir);                                             // released with the first holder

  const auto data = test::make_tiny_dataset("rel_train", 8);
  const std::string run = test::temp_dir("rel_train_run");
  auto cfg = test::tiny_train_config(data, run, 2);
  cfg.train.checkpoint_every = 1;
  {
    Trainer t(cfg);
    CHECK_THAT(error_of([&] { Trainer twin(cfg); }), Catch::Contains(run) && Catch::Contains("another process"));
    CHECK(t.run() == 0);
  }
  // `last` damaged: --resume auto continues from step_000002 and says so.
  const std::string last = run + "/checkpoints/last.safetensors";
  std::string bytes = test::read_bytes(last);
  bytes[bytes.size() / 2] ^= 0x40;
  test::write_bytes(last, bytes);
  {
    Trainer resumed(cfg);
    resumed.resume("auto");
    CHECK(resumed.step() == 2);
  }
  // Missing RNG state and a garbage optimizer state are named errors.
  Checkpoint ck = load_checkpoint(run + "/checkpoints/step_000002.safetensors");
  ck.tensors.erase("rng/torch");
  save_checkpoint(run + "/no_rng.safetensors", ck);
  ck = load_checkpoint(run + "/checkpoints/step_000002.safetensors");
  ck.tensors["optim/state"] = bytes_to_tensor("garbage, not an archive");
  save_checkpoint(run + "/bad_optim.safetensors", ck);
  {
    Trainer t(cfg);
    CHECK_THAT(error_of([&] { t.resume(run + "/no_rng.safetensors"); }), Catch::Contains("holds no RNG state"));
    CHECK_THAT(error_of([&] { t.resume(run + "/bad_optim.safetensors"); }),
               Catch::Contains("optimizer state ('optim/state') is unreadable"));
  }
  // A run folder that cannot be created (under a file) is an Error naming it, not a filesystem_error.
  test::write_bytes(run + "/file", "x");
  auto bad = cfg;
  bad.train.out = run + "/file/run";
  CHECK_THAT(error_of([&] { Trainer t(bad); }), Catch::Contains(run + "/file/run"));
}

TEST_CASE("reliability: NaN weights and a stored config far larger than the weights are refused before use",
          "[reliability][model]") {
  test::QuietLogs quiet;
  Checkpoint ck = one_step_checkpoint("rel_model");
  Checkpoint nan = ck;
  for (auto& [name, t] : nan.tensors)
    if (name.rfind("model/", 0) == 0 && t.is_floating_point()) t = torch::full_like(t, std::nan(""));
  CHECK_THAT(error_of([&] { load_pipeline(nan, "nan.safetensors"); }),
             Catch::Contains("nan.safetensors") && Catch::Contains("NaN"));
  auto config = nlohmann::json::parse(ck.config_json());
  config["model"]["encoder"]["vit"]["size"] = "custom";
  config["model"]["encoder"]["vit"]["embed_dim"] = 4096;
  config["model"]["encoder"]["vit"]["depth"] = 64;
  config["model"]["encoder"]["vit"]["heads"] = 64;
  ck.metadata["config"] = config.dump();
  CHECK_THAT(error_of([&] { load_pipeline(ck, "huge.safetensors"); }),
             Catch::Contains("huge.safetensors") && Catch::Contains("does not match the weights"));
}

TEST_CASE("reliability: an explicit prior.learned_weights override wins over the prior embedded in a checkpoint",
          "[reliability][model]") {
  test::QuietLogs quiet;
  Checkpoint ck = one_step_checkpoint("rel_prior_override");
  const std::string run = test::temp_dir("rel_prior_override_weights");
  torch::manual_seed(1);
  LearnedDepthNet embedded(8), other(8);
  std::map<std::string, torch::Tensor> other_weights;
  for (const auto& p : embedded->named_parameters(true)) ck.tensors["prior/" + p.key()] = p.value().detach();
  for (const auto& p : other->named_parameters(true)) other_weights[p.key()] = p.value().detach();
  write_safetensors(run + "/other.safetensors", other_weights);
  const std::vector<std::string> learned = {"prior.type=learned", "prior.learned_width=8"};
  auto with = learned;
  with.push_back("prior.learned_weights=" + run + "/other.safetensors");
  // Without the override the checkpoint is self-contained; with it, the named file is the prior.
  CHECK_THAT(load_pipeline(ck, "ck.safetensors", learned)->prior().describe(),
             Catch::Contains("embedded in the checkpoint"));
  const std::string described = load_pipeline(ck, "ck.safetensors", with)->prior().describe();
  CHECK_THAT(described, Catch::Contains(run + "/other.safetensors"));
  CHECK_THAT(described, !Catch::Contains("embedded"));
}

TEST_CASE("reliability: COLMAP and nerfstudio cameras with focal 0, NaN or a singular applied_transform",
          "[reliability][data]") {
  const std::string dir = test::temp_dir("rel_colmap");
  ColmapModel m;
  m.cameras[1] = {1, 1, 10, 10, {0, 5, 5, 5}};
  write_colmap_text(dir, m);
  CHECK_THAT(error_of([&] { read_colmap(dir); }), Catch::Contains("focal length that is not positive"));
  m.cameras[1] = {1, 1, 10, 10, {std::nan(""), 5, 5, 5}};
  write_colmap_binary(dir, m);
  CHECK_THAT(error_of([&] { read_colmap_binary(dir); }), Catch::Contains("non-finite parameter"));

  const auto g = test::make_tiny_dataset("rel_ns");
  const std::string scene = generated_eval_root(g.out, "atrium_nerfstudio") + "/scene_0";
  const std::string path = scene + "/transforms.json";
  auto j = nlohmann::json::parse(test::read_bytes(path));
  auto singular = j;
  singular["applied_transform"] = {{1, 0, 0, 0}, {0, 0, 0, 0}, {0, 0, 1, 0}};
  test::write_bytes(path, singular.dump());
  CHECK_THAT(error_of([&] { nerfstudio_sequence(scene, "x"); }),
             Catch::Contains(path) && Catch::Contains("'applied_transform' is singular"));
  auto typed = j;
  typed["camera_model"] = 3;
  test::write_bytes(path, typed.dump());
  CHECK_THAT(error_of([&] { nerfstudio_sequence(scene, "x"); }), Catch::Contains("'camera_model' must be a string"));
  auto path_number = j;
  path_number["frames"][0]["depth_file_path"] = 7;
  test::write_bytes(path, path_number.dump());
  CHECK_THAT(error_of([&] { nerfstudio_sequence(scene, "x"); }), Catch::Contains("'depth_file_path' must be a string"));
  auto zero = j;
  zero["fl_x"] = 0.0;
  test::write_bytes(path, zero.dump());
  CHECK_THAT(error_of([&] { nerfstudio_sequence(scene, "x"); }), Catch::Contains("focal length"));

  // CSV numbers (Hypersim's camera parameters) parse "nan" and "inf" too: refused by the reader.
  const std::string csv = dir + "/camera_parameters.csv";
  test::write_bytes(csv, "scene_name,settings_output_img_width\nai_001_001,nan\n");
  CHECK_THAT(error_of([&] { read_csv(csv).number(0, "settings_output_img_width"); }),
             Catch::Contains(csv) && Catch::Contains("expected a finite number"));
}

TEST_CASE("reliability: results logs drop out-of-range or foreign records, appends refuse symlinks, names are safe",
          "[reliability][eval]") {
  test::QuietLogs quiet;
  const std::string dir = test::temp_dir("rel_results");
  Manifest m;
  m.bin_counts = {1, 1};
  Pair p;
  p.bin = 1;
  p.baseline = 0.7;
  m.pairs = {p};
  const std::string log = dir + "/results_x.jsonl";
  const std::string ok = R"({"index":0,"bin":1,"baseline":0.7,"psnr":20.5,"ssim":0.6,"infer_ms":1,"render_ms":1,)"
                         R"("gaussians":10,"mask_fraction":0.5})";
  test::write_bytes(log, ok + "\n" + R"({"index":0,"bin":1,"baseline":0.7,"psnr":1e308,"ssim":0.6,"infer_ms":1,)" +
                             R"("render_ms":1,"gaussians":10,"mask_fraction":0.5})" + "\n");
  CHECK(ResultsLog(log, [&](const PairResult& r) { return check_against_manifest(r, m); }).done().size() == 1);
  test::write_bytes(log, R"({"index":0,"bin":1,"baseline":0.7,"psnr":1e308,"ssim":0.6,"infer_ms":1,"render_ms":1,)"
                         R"("gaussians":10,"mask_fraction":0.5})"
                         "\n");
  CHECK(ResultsLog(log).done().empty());
  std::string bin99 = ok;
  bin99.replace(bin99.find("\"bin\":1"), 7, "\"bin\":99");
  test::write_bytes(log, bin99 + "\n");
  CHECK(ResultsLog(log).done().size() == 1);  // in range for a log alone ...
  CHECK(ResultsLog(log, [&](const PairResult& r) { return check_against_manifest(r, m); }).done().empty());  // not here
  PairResult foreign;
  foreign.index = 5;
  CHECK(check_against_manifest(foreign, m).find("not in the manifest") != std::string::npos);

  const std::string target = dir + "/elsewhere.txt", link = dir + "/train_log.jsonl";
  test::write_bytes(target, "");
  fs::create_symlink(target, link);
  CHECK_THAT(error_of([&] { JsonlWriter w(link); }), Catch::Contains("symbolic link"));
  CHECK(test::read_bytes(target).empty());

  CHECK(safe_name("../../x") == "______x");
  EvalConfig config;
  config.scoring.out = dir + "/eval";
  config.scoring.lpips = {};
  config.datasets.resize(1);
  config.datasets[0].name = "../../x";
  const Evaluator ev(config);
  CHECK(fs::path(ev.dataset_dir(0)).parent_path() == fs::path(config.scoring.out));
  CHECK(fs::path(ev.results_path(0, "../m")).parent_path() == fs::path(ev.dataset_dir(0)));
}
