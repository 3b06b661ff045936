// Outputs are all or nothing (issue 74): predict's PLY and camera JSON appear together or not at all, an interrupted
// render leaves a playable video or none, and SIGINT/SIGTERM leave no temporary behind.
#include <catch2/catch.hpp>

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <thread>

#include <torch/torch.h>
#include <opencv2/videoio.hpp>

#include "core/error.h"
#include "io/atomic_file.h"
#include "io/ply.h"
#include "support/test_util.h"
#include "support/tiny_dataset.h"
#include "support/tiny_model.h"
#include "train/trainer.h"

using namespace isplat;
namespace fs = std::filesystem;

namespace {

std::string aon_tool() {
  return (fs::path(ISPLAT_BINARY_DIR) / "infinisplat").string();
}

// Starts the tool with `args` (no shell), its output into `log`; returns its pid.
pid_t aon_spawn(const std::vector<std::string>& args, const std::string& log) {
  // A signal the test sends before the child has exec'd must not reach the test framework's handlers (they allocate,
  // and a forked child of a threaded process may hang in malloc): held off until the child has reset them.
  sigset_t held, before;
  sigemptyset(&held);
  sigaddset(&held, SIGINT);
  sigaddset(&held, SIGTERM);
  ::pthread_sigmask(SIG_BLOCK, &held, &before);
  const pid_t pid = ::fork();
  if (pid != 0) ::pthread_sigmask(SIG_SETMASK, &before, nullptr);
  if (pid == 0) {
    ::signal(SIGINT, SIG_DFL);
    ::signal(SIGTERM, SIG_DFL);
    ::pthread_sigmask(SIG_SETMASK, &before, nullptr);
    const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(fd, 1);
    ::dup2(fd, 2);
    std::vector<char*> argv;
    const std::string tool = aon_tool();
    argv.push_back(const_cast<char*>(tool.c_str()));
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(tool.c_str(), argv.data());
    ::_exit(127);
  }
  return pid;
}

// The exit status as a shell reads it: the code, or 128 + the signal that ended the process.
int aon_wait(pid_t pid) {
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

std::vector<std::string> aon_temporaries(const std::string& dir) {
  std::vector<std::string> found;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (is_temporary_name(e.path().filename().string())) found.push_back(e.path().string());
  return found;
}

void aon_wait_for(const std::string& path, double seconds) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (!fs::exists(path) && std::chrono::steady_clock::now() < end)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
}

}  // namespace

TEST_CASE("all or nothing: SIGTERM removes the temporaries a process has open and ends it by the signal",
          "[reliability][allornothing]") {
  const std::string dir = test::temp_dir("aon_signal");
  const pid_t child = ::fork();
  if (child == 0) {
    remove_temporaries_on_signal();
    AtomicPath ply(dir + "/scene.ply"), camera(dir + "/scene.camera.json");
    test::write_bytes(ply.temp(), "half a scene");
    test::write_bytes(camera.temp(), "{}");
    test::write_bytes(dir + "/ready", "");
    for (;;) ::pause();
  }
  aon_wait_for(dir + "/ready", 10);
  REQUIRE(fs::exists(dir + "/ready"));
  CHECK(aon_temporaries(dir).size() == 2);
  ::kill(child, SIGTERM);
  CHECK(aon_wait(child) == 128 + SIGTERM);
  CHECK(aon_temporaries(dir).empty());
  CHECK_FALSE(fs::exists(dir + "/scene.ply"));
  CHECK_FALSE(fs::exists(dir + "/scene.camera.json"));
}

TEST_CASE("all or nothing: predict writes the PLY and its camera JSON both or neither (render and export stop clean)",
          "[reliability][allornothing][use]") {
  test::QuietLogs quiet;
  const auto data = test::make_tiny_dataset("aon_data", 8);
  const std::string run = test::temp_dir("aon_run");
  TrainConfig c = test::tiny_train_config(data, run, 1);
  c.data.tuples.targets = 1;
  c.model.sampler.budget = 2000;
  Trainer(c).save(run + "/ck.safetensors");
  const std::string scene = generated_eval_root(data.out, "courtyard_colmap") + "/scene_0";
  const std::string out = test::temp_dir("aon_out"), log = out + "/log.txt";
  const std::vector<std::string> predict = {"predict",
                                            "--checkpoint",
                                            run + "/ck.safetensors",
                                            "--image",
                                            scene + "/images/IMG_0002.jpg",
                                            "--depth",
                                            scene + "/depth/IMG_0002.exr",
                                            "--hfov",
                                            "65"};
  const auto with = [](std::vector<std::string> a, const std::vector<std::string>& more) {
    a.insert(a.end(), more.begin(), more.end());
    return a;
  };

  // The camera JSON cannot be written (a folder holds its name): the older PLY stays as it was, nothing is left.
  const std::string old_ply = "an older scene";
  test::write_bytes(out + "/scene.ply", old_ply);
  fs::create_directories(out + "/scene.camera.json");
  CHECK(aon_wait(aon_spawn(with(predict, {"--out", out + "/scene.ply"}), log)) == 1);
  CHECK_THAT(test::read_bytes(log), Catch::Contains("scene.camera.json"));
  CHECK(test::read_bytes(out + "/scene.ply") == old_ply);
  CHECK(aon_temporaries(out).empty());
  fs::remove(out + "/scene.camera.json");
  REQUIRE(aon_wait(aon_spawn(with(predict, {"--out", out + "/scene.ply"}), log)) == 0);
  const Gaussians g = read_ply(out + "/scene.ply");
  CHECK(fs::exists(out + "/scene.camera.json"));

  // SIGTERM at any moment: both files or neither, and no temporary.
  for (int delay_ms : {150, 400, 700, 1000, 1500}) {
    const std::string ply = cat(out, "/killed_", delay_ms, ".ply");
    const pid_t pid = aon_spawn(with(predict, {"--out", ply}), log);
    std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms));
    ::kill(pid, SIGTERM);
    const int rc = aon_wait(pid);
    INFO("delay " << delay_ms << " ms, exit " << rc);
    CHECK((rc == 0 || rc == 128 + SIGTERM));
    const std::string camera = cat(out, "/killed_", delay_ms, ".camera.json");
    CHECK(fs::exists(ply) == fs::exists(camera));
    if (fs::exists(ply)) CHECK(read_ply(ply).count() == g.count());
    CHECK(aon_temporaries(out).empty());
  }

  // render: SIGTERM after a few frames finishes the video with them (it plays), says so and exits 128 + 15.
  const std::string frames = out + "/orbit";
  const pid_t render = aon_spawn(
      {"render", "--ply", out + "/scene.ply", "--frames", "3000", "--width", "320", "--height", "240", "--out", frames},
      log);
  aon_wait_for(frames + "/frame_0002.png", 60);
  ::kill(render, SIGTERM);
  CHECK(aon_wait(render) == 128 + SIGTERM);
  CHECK_THAT(test::read_bytes(log), Catch::Contains("interrupted") && Catch::Contains("plays"));
  int64_t pngs = 0;
  for (const auto& e : fs::directory_iterator(frames)) pngs += e.path().extension() == ".png";
  CHECK(pngs >= 3);
  CHECK(pngs < 3000);
  cv::VideoCapture video(frames + "/video.mp4");
  REQUIRE(video.isOpened());
  CHECK(static_cast<int64_t>(video.get(cv::CAP_PROP_FRAME_COUNT)) == pngs);
  CHECK(aon_temporaries(frames).empty());
  // A second signal ends it at once: no video.mp4 without its index, no temporary.
  const std::string twice = out + "/twice";
  const pid_t render2 = aon_spawn(
      {"render", "--ply", out + "/scene.ply", "--frames", "3000", "--width", "320", "--height", "240", "--out", twice},
      log);
  aon_wait_for(twice + "/frame_0001.png", 60);
  ::kill(render2, SIGINT);
  ::kill(render2, SIGINT);
  const int rc2 = aon_wait(render2);
  CHECK((rc2 == 128 + SIGINT));
  if (fs::exists(twice + "/video.mp4")) CHECK(cv::VideoCapture(twice + "/video.mp4").isOpened());
  CHECK(aon_temporaries(twice).empty());

  // export: SIGTERM while the output is written leaves neither a temporary nor a partial file.
  const int64_t n = 400000;
  torch::manual_seed(0);
  const Gaussians big{torch::randn({n, 3}) + torch::tensor({0.0, 0.0, 4.0}), torch::rand({n, 3}) * 0.05 + 1e-3,
                      torch::randn({n, 4}), torch::rand({n, 3}) * 0.9 + 0.05, torch::rand({n}) * 0.9 + 0.05};
  write_ply(out + "/big.ply", big, false);
  const std::string exports = out + "/exports";
  fs::create_directories(exports);
  int64_t caught = 0;  // runs killed while their temporary existed
  for (int attempt = 0; attempt < 6; ++attempt) {
    const std::string splat = cat(exports, "/big_", attempt, ".splat");
    const pid_t pid = aon_spawn({"export", "--ply", out + "/big.ply", "--format", "splat", "--out", splat}, log);
    if (attempt < 4) {  // the moment the temporary appears
      const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(20);
      while (aon_temporaries(exports).empty() && !fs::exists(splat) && std::chrono::steady_clock::now() < end) {
      }
      caught += !aon_temporaries(exports).empty();
    } else {
      std::this_thread::sleep_for(std::chrono::milliseconds(attempt == 4 ? 100 : 300));
    }
    ::kill(pid, SIGTERM);
    const int rc = aon_wait(pid);
    INFO("attempt " << attempt << ", exit " << rc);
    CHECK((rc == 0 || rc == 128 + SIGTERM));
    if (fs::exists(splat)) CHECK(fs::file_size(splat) == static_cast<uintmax_t>(32 * n));
    CHECK(aon_temporaries(exports).empty());
  }
  CHECK(caught > 0);
}
