// Nothing the user wrote is lost (issue 74): cleanups remove only the program's own temporaries of ended writers,
// outputs that are one of the inputs are refused, gallery cleanup is exact, scoring.out is locked.
#include <catch2/catch.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <map>

#include <torch/torch.h>

#include "core/config.h"
#include "core/error.h"
#include "eval/evaluator.h"
#include "eval/pairs.h"
#include "io/atomic_file.h"
#include "io/folder_lock.h"
#include "io/ply.h"
#include "support/test_util.h"
#include "support/tiny_dataset.h"
#include "support/tiny_model.h"
#include "train/trainer.h"

using namespace isplat;
namespace fs = std::filesystem;

namespace {

// The pid of a process that has ended (forked, exited and reaped): what a killed writer leaves in its names.
long ndl_dead_pid() {
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  int status = 0;
  ::waitpid(child, &status, 0);
  return static_cast<long>(child);
}

std::string ndl_tool() {
  return (fs::path(ISPLAT_BINARY_DIR) / "infinisplat").string();
}

// Runs a shell command with its output into `log`; returns the exit status.
int ndl_run(const std::string& command, const std::string& log) {
  const int rc = std::system((command + " > " + log + " 2>&1").c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : 128 + WTERMSIG(rc);
}

Gaussians ndl_gaussians(int64_t n) {
  torch::manual_seed(0);
  return {torch::randn({n, 3}) * 0.3 + torch::tensor({0.0, 0.0, 3.0}), torch::rand({n, 3}) * 0.05 + 1e-3,
          torch::randn({n, 4}), torch::rand({n, 3}) * 0.9 + 0.05, torch::rand({n}) * 0.9 + 0.05};
}

}  // namespace

TEST_CASE("no data loss: temporaries are recognized by the program's exact marker", "[reliability][nodataloss]") {
  long pid = 0;
  CHECK(is_temporary_name(".config.isplat-tmp4242_0.json", &pid));
  CHECK(pid == 4242);
  CHECK(is_temporary_name(".last.isplat-tmp17_3.safetensors"));
  CHECK(is_temporary_name(".log.isplat-tmp17_3"));
  for (const char* user :
       {".draft.tmp.txt", ".notes.tmp", ".last.tmp4242_0.safetensors", ".x.isplat-tmp_0.json", ".x.isplat-tmp12_.json",
        ".x.isplat-tmp12_0.json.bak", "x.isplat-tmp12_0.json", ".x.isplat-tmpab_0.json", ".isplat-tmp12_0.json"})
    CHECK_FALSE(is_temporary_name(user));
  // The names writes really use.
  const std::string dir = test::temp_dir("ndl_names");
  AtomicPath a(dir + "/scene.ply");
  CHECK(is_temporary_name(fs::path(a.temp()).filename().string(), &pid));
  CHECK(pid == static_cast<long>(getpid()));
}

TEST_CASE("no data loss: train.out in a user's folder removes only temporaries of ended writers",
          "[reliability][nodataloss][train]") {
  test::QuietLogs quiet;
  const std::string dir = test::temp_dir("ndl_user_folder");
  const long dead = ndl_dead_pid();
  const std::vector<std::string> users = {".draft.tmp.txt", ".notes.tmp", ".a.tmp12_3.txt", "notes.txt",
                                          cat(".x.isplat-tmp", dead, "_0.json.bak")};
  const std::vector<std::string> ours_dead = {cat(".config.isplat-tmp", dead, "_0.json"),
                                              cat(".train_log.isplat-tmp", dead, "_4.jsonl")};
  // Counter 999: the trainer's own first writes in this process use low counters (and rename those files away).
  const std::vector<std::string> ours_live = {cat(".config.isplat-tmp", getpid(), "_999.json"),
                                              ".config.isplat-tmp1_0.json"};  // pid 1 is alive
  for (const auto& f : users) test::write_bytes(dir + "/" + f, "the user's");
  for (const auto& f : ours_dead) test::write_bytes(dir + "/" + f, "half");
  for (const auto& f : ours_live) test::write_bytes(dir + "/" + f, "being written");
  // Training fails on an unrelated error (no data) after its cleanup ran.
  TrainConfig cfg = test::tiny_train_config(GenerateOptions{}, dir, 1);
  cfg.data.hypersim.root = dir + "/no_such_data";
  CHECK_THROWS(Trainer(cfg));
  for (const auto& f : users) {
    INFO(f);
    CHECK(test::read_bytes(dir + "/" + f) == "the user's");
  }
  for (const auto& f : ours_dead) CHECK_FALSE(fs::exists(dir + "/" + f));
  for (const auto& f : ours_live) CHECK(fs::exists(dir + "/" + f));
  CHECK(remove_stale_temporaries(dir) == 0);
}

TEST_CASE("no data loss: predict, export and render refuse an output that is one of their inputs",
          "[reliability][nodataloss][use]") {
  const std::string dir = test::temp_dir("ndl_collide");
  const std::string ck = dir + "/ck.safetensors", photo = dir + "/photo.png";
  test::write_bytes(ck, "weights");
  test::write_bytes(photo, "pixels");
  const std::string log = dir + "/log.txt";
  const std::string predict = ndl_tool() + " predict --checkpoint " + ck + " --image " + photo;
  // The same path, another spelling of it, and the camera JSON written beside the PLY.
  CHECK(ndl_run(predict + " --out " + ck, log) == 1);
  CHECK_THAT(test::read_bytes(log), Catch::Contains("--out " + ck) && Catch::Contains("--checkpoint " + ck));
  CHECK(ndl_run(predict + " --out " + dir + "/./photo.png", log) == 1);
  CHECK_THAT(test::read_bytes(log), Catch::Contains("--image " + photo));
  test::write_bytes(dir + "/cam.camera.json", "a photo named so");
  CHECK(ndl_run(ndl_tool() + " predict --checkpoint " + ck + " --image " + dir + "/cam.camera.json --out " + dir +
                    "/cam.ply",
                log) == 1);
  CHECK_THAT(test::read_bytes(log), Catch::Contains("camera JSON") && Catch::Contains("cam.camera.json"));
  // A hard link and a symlinked folder: the same inode under another name.
  fs::create_hard_link(ck, dir + "/linked.ply");
  CHECK(ndl_run(predict + " --out " + dir + "/linked.ply", log) == 1);
  CHECK_THAT(test::read_bytes(log), Catch::Contains("--checkpoint"));
  fs::create_directory_symlink(dir, dir + "/alias");
  CHECK(ndl_run(predict + " --out " + dir + "/alias/ck.safetensors", log) == 1);
  CHECK(test::read_bytes(ck) == "weights");
  CHECK(test::read_bytes(photo) == "pixels");

  // export: --out over --ply or over the camera JSON it reads.
  const std::string ply = dir + "/scene.ply";
  write_ply(ply, ndl_gaussians(40), false);
  const std::string bytes = test::read_bytes(ply);
  for (const char* format : {"splat", "ply-sh3"}) {
    CHECK(ndl_run(ndl_tool() + " export --ply " + ply + " --format " + format + " --out " + ply, log) == 1);
    CHECK_THAT(test::read_bytes(log), Catch::Contains("--ply " + ply));
  }
  CHECK(test::read_bytes(ply) == bytes);
  // render: a PLY kept in the output folder under a name render writes.
  fs::create_directories(dir + "/frames");
  fs::copy_file(ply, dir + "/frames/frame_0001.png");
  CHECK(ndl_run(ndl_tool() + " render --ply " + dir + "/frames/frame_0001.png --frames 3 --no-video --out " + dir +
                    "/frames",
                log) == 1);
  CHECK_THAT(test::read_bytes(log), Catch::Contains("frame_0001.png") && Catch::Contains("--ply"));
  CHECK(test::read_bytes(dir + "/frames/frame_0001.png") == bytes);
  CHECK_FALSE(fs::exists(dir + "/frames/frame_0000.png"));
}

TEST_CASE("no data loss: a method's gallery cleanup leaves another method's panels, and scoring.out is locked",
          "[reliability][nodataloss][eval]") {
  test::QuietLogs quiet;
  CHECK(gallery_panel_method("m_worst_psnr1_pair3.png") == "m");
  CHECK(gallery_panel_method("m_worst_a_worst_psnr1_pair3.png") == "m_worst_a");
  CHECK(gallery_panel_method("m_worst_a_worst_holes12_pair30.png") == "m_worst_a");
  CHECK(gallery_panel_method("m_worst_psnr1_pair3.png.bak").empty());
  CHECK(gallery_panel_method("m_pair3.png").empty());

  const auto g = test::make_tiny_dataset("ndl_gallery", 16);
  EvalConfig c;
  c.datasets = {test::tiny_courtyard_set(g)};
  // "m_worst_a" first: before the fix, "m"'s cleanup (prefix "m_worst_") then deleted its panels.
  c.methods = {named_method("m_worst_a", "lift"), named_method("m", "lift")};
  c.protocol.pairs_per_bin = 2;
  c.scoring.out = test::temp_dir("ndl_gallery_out");
  c.scoring.lpips = {};
  c.scoring.examples = 0;
  c.scoring.gallery = 1;
  Evaluator(c).run();
  const auto panels = [&] {
    std::map<std::string, int64_t> by_method;
    for (const auto& e : fs::directory_iterator(c.scoring.out + "/courtyard/gallery"))
      ++by_method[gallery_panel_method(e.path().filename().string())];
    return by_method;
  };
  const auto first = panels();
  CHECK(first.count("m") == 1);
  REQUIRE(first.count("m_worst_a") == 1);
  CHECK(first.at("m_worst_a") == first.at("m"));
  Evaluator(c).run();  // a rerun keeps both
  CHECK(panels() == first);

  // A second evaluation into the same folder fails at once, naming it and the holder's pid; in another process too.
  {
    FolderLock held(c.scoring.out);
    CHECK_THAT(test::error_of([&] { Evaluator(c).run(); }),
               Catch::Contains("scoring.out " + c.scoring.out) && Catch::Contains(cat("pid ", getpid())));
    const std::string config = c.scoring.out + "/../ndl_eval.json";
    write_file_atomic(config, config_to_json(c).dump(2));
    const std::string log = c.scoring.out + "/../ndl_eval.txt";
    CHECK(ndl_run((fs::path(ISPLAT_BINARY_DIR) / "infinisplat-eval").string() + " --config " + config, log) == 1);
    CHECK_THAT(test::read_bytes(log), Catch::Contains(c.scoring.out) && Catch::Contains(cat("pid ", getpid())));
  }
  CHECK_NOTHROW(Evaluator(c).run());  // released with its holder
}

TEST_CASE("no data loss: scores are tied to the dataset they were computed from", "[reliability][nodataloss][eval]") {
  test::QuietLogs quiet;
  const auto a = test::make_tiny_dataset("ndl_data_a", 16), b = test::make_tiny_dataset("ndl_data_b", 12);
  EvalConfig c;
  EvalDatasetOptions d;
  d.name = "courtyard";
  d.format = "colmap";
  d.root = generated_eval_root(a.out, "courtyard_colmap");
  c.datasets = {d};
  c.methods = {named_method("lift", "lift")};
  c.protocol.pairs_per_bin = 2;
  c.scoring.out = test::temp_dir("ndl_data_out");
  c.scoring.lpips = {};
  c.scoring.examples = 0;
  Evaluator(c).run();
  const std::string dir = c.scoring.out + "/courtyard", manifest = dir + "/manifest.json",
                    results = dir + "/results_lift.jsonl", report = c.scoring.out + "/report.md";
  const auto fingerprint = read_manifest(manifest).dataset_fingerprint;
  REQUIRE(fingerprint.is_object());
  CHECK(fingerprint.at("root") == fs::weakly_canonical(d.root).string());
  CHECK(fingerprint.at("frames").get<int64_t>() > 0);
  CHECK(nlohmann::json::parse(test::read_bytes(results + ".method.json")).at("dataset_fingerprint") == fingerprint);
  const std::string scored = test::read_bytes(results), reported = test::read_bytes(report);

  // Another dataset under the same name and scoring.out: stopped, naming what changed; nothing is rewritten.
  EvalConfig other = c;
  other.datasets[0].root = generated_eval_root(b.out, "courtyard_colmap");
  CHECK_THAT(test::error_of([&] { Evaluator(other).run(); }),
             Catch::Contains("dataset 'courtyard' changed") && Catch::Contains("root") &&
                 Catch::Contains(fs::weakly_canonical(other.datasets[0].root).string()) &&
                 Catch::Contains("frame list") && Catch::Contains(dir));
  CHECK(test::read_bytes(results) == scored);
  CHECK(test::read_bytes(report) == reported);

  // The same root with a changed file: an image's time, then a COLMAP model file's content.
  std::string image;
  for (const auto& e : fs::recursive_directory_iterator(d.root))
    if (e.path().extension() == ".jpg" || e.path().extension() == ".png") image = e.path().string();
  REQUIRE(!image.empty());
  const auto time = fs::last_write_time(image);
  fs::last_write_time(image, time + std::chrono::hours(1));
  CHECK_THAT(test::error_of([&] { Evaluator(c).run(); }), Catch::Contains("image or depth files"));
  fs::last_write_time(image, time);
  CHECK_NOTHROW(Evaluator(c).run());  // as it was: the scores are reused
  CHECK(test::read_bytes(results) == scored);
  std::string model;
  for (const auto& e : fs::recursive_directory_iterator(d.root))
    if (e.path().filename() == "images.txt" || e.path().filename() == "images.bin") model = e.path().string();
  REQUIRE(!model.empty());
  const std::string model_bytes = test::read_bytes(model);
  test::write_bytes(model, model_bytes + (fs::path(model).extension() == ".txt" ? "# edited\n" : "x"));
  CHECK_THAT(test::error_of([&] { Evaluator(c).run(); }),
             Catch::Contains("model file") && Catch::Contains(fs::path(model).filename().string() + " changed"));
  test::write_bytes(model, model_bytes);

  // Without its manifest, the results' stamp still knows the data they were scored on.
  fs::remove(manifest);
  CHECK_THAT(test::error_of([&] { Evaluator(other).run(); }),
             Catch::Contains("results_lift.jsonl.method.json") && Catch::Contains("root"));
  CHECK_FALSE(fs::exists(manifest));  // no manifest of the other data beside the old scores
  CHECK(test::read_bytes(results) == scored);
  // A manifest written before fingerprints adopts the data it is run with.
  Evaluator(c).run();
  auto js = nlohmann::json::parse(test::read_bytes(manifest));
  js.erase("dataset_fingerprint");
  write_file_atomic(manifest, js.dump(2));
  Evaluator(c).run();
  CHECK(read_manifest(manifest).dataset_fingerprint == fingerprint);
  CHECK(test::read_bytes(results) == scored);
}
