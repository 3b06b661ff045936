// Every error names something the user can act on (issue 74, items 4 and 5): numeric options out of range name the
// option and its range, a config that is not a regular JSON file fails at once, a depth map of another framing is
// refused, and failures that cannot name their cause say what the program was doing.
#include <catch2/catch.hpp>

#include <sys/stat.h>
#include <sys/wait.h>

#include <chrono>
#include <filesystem>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "io/depth_io.h"
#include "support/test_util.h"
#include "support/tiny_dataset.h"
#include "support/tiny_model.h"
#include "train/trainer.h"

using namespace isplat;
namespace fs = std::filesystem;

namespace {

std::string ne_tool(const std::string& name) {
  return (fs::path(ISPLAT_BINARY_DIR) / name).string();
}

// Runs a command (bounded by `timeout`, so a hang fails the test instead of stalling the suite) with its output in
// `log`; returns the exit status (124: timed out).
int ne_run(const std::string& command, const std::string& log, int seconds = 60) {
  const int rc = std::system(
      cat("ulimit -v 6291456; timeout -s KILL ", seconds, " ", command, " > ", log, " 2>&1 < /dev/null").c_str());
  if (WIFEXITED(rc)) return WEXITSTATUS(rc);
  return 128 + WTERMSIG(rc);
}

}  // namespace

TEST_CASE("named errors: numeric options out of range name the option and its range", "[namederrors][cli]") {
  const std::string dir = test::temp_dir("ne_ranges"), log = dir + "/log.txt";
  const std::string predict =
      ne_tool("infinisplat") + " predict --checkpoint none.safetensors --image none.jpg --out " + dir + "/x.ply ";
  const std::string render = ne_tool("infinisplat") + " render --ply none.ply --out " + dir + "/frames ";
  struct Case {
    std::string command, option, says;
  };
  const std::vector<Case> cases = {
      {predict + "--fx 0", "--fx 0", "outside its range"},
      {predict + "--fx -500", "--fx -500", "outside its range"},
      {predict + "--fx nan", "--fx nan", "outside its range"},
      {predict + "--fx 1e400", "--fx", "expected a number"},
      {predict + "--hfov 0", "--hfov 0", "outside its range [1, 179] (degrees)"},
      {predict + "--hfov 240", "--hfov 240", "outside its range"},
      {predict + "--fx 500 --cx -3", "--cx -3", "outside its range"},
      {predict + "--cx 10", "--fx", "give --fx too"},
      {predict + "--width 64", "--width and --height", "together"},
      {predict + "--width 40 --height 32", "--width 40", "multiples of 16"},
      {predict + "--threads -1", "--threads -1", "outside its range [0, 1024]"},
      {predict + "--threads 5000", "--threads 5000", "outside its range"},
      {predict + "--prune-opacity 2", "--prune-opacity 2", "outside its range"},
      {render + "--width 0 --height 48", "--width 0", "outside its range"},
      {render + "--width 64", "--width and --height", "together"},
      {render + "--width 60000 --height 60000", "--width x --height", "runtime.max_image_pixels"},
      {render + "--frames 0", "--frames 0", "outside its range"},
      {render + "--fps -1", "--fps -1", "outside its range"},
      {render + "--hfov 0", "--hfov 0", "outside its range"},
      {render + "--threads -4", "--threads -4", "outside its range"},
      {ne_tool("infinisplat") + " export --ply none.ply --format splat --out " + dir + "/x.splat --fov 0", "--fov 0",
       "outside its range"},
      {ne_tool("infinisplat") + " export-onnx --checkpoint none --out " + dir + "/x.onnx --width 40", "--width 40",
       "multiples of 16"},
      {ne_tool("infinisplat") + " export-onnx --checkpoint none --out " + dir + "/x.onnx --opset 5", "--opset 5",
       "outside its range"},
      {ne_tool("infinisplat") + " version --threads -2", "--threads -2", "outside its range"},
      {ne_tool("infinisplat-train") + " --print-config --threads -3", "--threads -3", "outside its range"},
      {ne_tool("infinisplat-eval") + " --print-config --merge -1", "--merge -1", "outside its range"},
  };
  for (const Case& c : cases) {
    INFO(c.command);
    CHECK(ne_run(c.command, log) == 1);
    const std::string text = test::read_bytes(log);
    CHECK_THAT(text, Catch::Contains(c.option) && Catch::Contains(c.says));
  }
}

TEST_CASE("named errors: a config or base that is not a regular JSON file fails at once, naming it",
          "[namederrors][config]") {
  const std::string dir = test::temp_dir("ne_config"), log = dir + "/log.txt";
  REQUIRE(::mkfifo((dir + "/fifo.json").c_str(), 0600) == 0);
  fs::create_directory(dir + "/folder.json");
  fs::create_symlink(dir + "/loop_b.json", dir + "/loop_a.json");
  fs::create_symlink(dir + "/loop_a.json", dir + "/loop_b.json");
  test::write_bytes(dir + "/base_zero.json", R"({"base": "/dev/zero"})");
  test::write_bytes(dir + "/base_fifo.json", R"({"base": "fifo.json"})");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"/dev/zero", "/dev/zero: is a device, not a regular JSON file"},
      {dir + "/fifo.json", "fifo.json: is a FIFO (named pipe), not a regular JSON file"},
      {dir + "/folder.json", "folder.json: is a folder, not a regular JSON file"},
      {dir + "/loop_a.json", "loop_a.json: symbolic link loop"},
      {dir + "/base_zero.json", "/dev/zero: is a device"},
      {dir + "/base_fifo.json", "fifo.json: is a FIFO"},
  };
  for (const auto& [config, says] : cases) {
    for (const char* exe : {"infinisplat-train", "infinisplat-eval"}) {
      INFO(exe << " --config " << config);
      const auto start = std::chrono::steady_clock::now();
      CHECK(ne_run(ne_tool(exe) + " --print-config --config " + config, log, 30) == 1);
      CHECK(std::chrono::steady_clock::now() - start < std::chrono::seconds(20));  // at once, never a read to the end
      CHECK_THAT(test::read_bytes(log), Catch::Contains(says));
    }
  }
  // An input file that is a FIFO blocks no reader either.
  CHECK(ne_run(ne_tool("infinisplat") + " render --ply " + dir + "/fifo.json --out " + dir + "/frames", log, 30) == 1);
  CHECK_THAT(test::read_bytes(log), Catch::Contains("fifo.json: is a FIFO"));
}

TEST_CASE("named errors: predict refuses a depth map of another aspect and a principal point outside the photo",
          "[namederrors][predict]") {
  test::QuietLogs quiet;
  const auto data = test::make_tiny_dataset("ne_predict", 8);
  const std::string run = test::temp_dir("ne_predict_run"), log = run + "/log.txt";
  TrainConfig c = test::tiny_train_config(data, run, 1);
  c.model.sampler.budget = 500;
  const std::string ck = run + "/ck.safetensors";
  Trainer(c).save(ck);
  const std::string scene = generated_eval_root(data.out, "courtyard_colmap") + "/scene_0";
  const std::string photo = scene + "/images/IMG_0001.jpg";
  const cv::Mat image = cv::imread(photo);
  REQUIRE(!image.empty());
  // The photo's depth at its own size and resized to half: both read. Cropped to a square: another framing.
  const DepthMap depth = read_depth_exr(scene + "/depth/IMG_0001.exr");
  REQUIRE(depth.depth.cols == image.cols);
  cv::Mat half, square = depth.depth(cv::Rect(0, 0, depth.depth.rows, depth.depth.rows)).clone();
  cv::resize(depth.depth, half, cv::Size(image.cols / 2, image.rows / 2), 0, 0, cv::INTER_NEAREST);
  write_depth_exr(run + "/half.exr", half);
  write_depth_exr(run + "/square.exr", square);
  const std::string predict =
      ne_tool("infinisplat") + " predict --threads 1 --checkpoint " + ck + " --image " + photo + " --hfov 60 ";
  CHECK(ne_run(predict + "--depth " + run + "/half.exr --out " + run + "/half.ply", log, 300) == 0);
  CHECK(ne_run(predict + "--depth " + run + "/square.exr --out " + run + "/square.ply", log, 300) == 1);
  CHECK_THAT(test::read_bytes(log),
             Catch::Contains("square.exr") && Catch::Contains("IMG_0001.jpg") && Catch::Contains("aspects differ"));
  CHECK_FALSE(fs::exists(run + "/square.ply"));
  const std::string beyond = cat(" --fx 50 --cx ", image.cols + 10, " ");
  CHECK(ne_run(predict + "--depth " + run + "/half.exr" + beyond + "--out " + run + "/cx.ply", log, 300) == 1);
  CHECK_THAT(test::read_bytes(log), Catch::Contains("--cx") && Catch::Contains("outside the photo"));
}
