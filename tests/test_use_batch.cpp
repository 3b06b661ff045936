// predict on many inputs (issue 70): a folder, a list file or a video in one process with the model loaded once,
// one PLY and camera JSON per input, resumable; --max-gaussians bounds the output by the support budget.
#include <catch2/catch.hpp>

#include <sys/wait.h>

#include <filesystem>
#include <regex>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "core/error.h"
#include "io/ply.h"
#include "support/test_util.h"
#include "support/tiny_dataset.h"
#include "support/tiny_model.h"
#include "train/trainer.h"

using namespace isplat;
namespace fs = std::filesystem;

namespace {

int pb_run(const std::string& args, const std::string& log) {
  const std::string tool = (fs::path(ISPLAT_BINARY_DIR) / "infinisplat").string();
  const int rc = std::system((tool + " predict " + args + " > " + log + " 2>&1").c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : 128 + WTERMSIG(rc);
}

int64_t pb_count(const std::string& text, const std::string& what) {
  int64_t n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

// The number after `key` on the report line that starts with it ("supports     2000").
int64_t pb_value(const std::string& text, const std::string& key) {
  const size_t at = text.find(key);
  return at == std::string::npos ? -1 : std::stoll(text.substr(at + key.size()));
}

}  // namespace

TEST_CASE("predict batch: a folder, a list and a video in one process, resumable, and --max-gaussians caps the budget",
          "[use][predict]") {
  test::QuietLogs quiet;
  const auto data = test::make_tiny_dataset("pb_data", 8);
  const std::string run = test::temp_dir("pb_run");
  TrainConfig c = test::tiny_train_config(data, run, 1);
  c.data.tuples.targets = 1;
  c.model.sampler.budget = 2000;
  const std::string ck = run + "/ck.safetensors";
  Trainer(c).save(ck);
  const std::string images = generated_eval_root(data.out, "courtyard_colmap") + "/scene_0/images";
  const std::string out = test::temp_dir("pb_out"), log = out + "/log.txt";
  // An RGB prior (the untrained learned net): inputs without depth files.
  const std::string base = "--checkpoint " + ck + " --set prior.type=learned --set prior.learned_width=8 ";

  // A folder: every image once, the model loaded once; a second run skips them all; a lost sidecar redoes one.
  const std::string folder = out + "/photos";
  fs::create_directories(folder);
  for (const char* f : {"IMG_0001.jpg", "IMG_0002.jpg", "IMG_0003.jpg"})
    fs::copy_file(images + "/" + f, folder + "/" + f);
  test::write_bytes(folder + "/notes.md", "not an image");
  REQUIRE(pb_run(base + "--image " + folder + " --out " + out + "/scenes", log) == 0);
  std::string report = test::read_bytes(log);
  CHECK(pb_count(report, "model: ") == 1);
  CHECK_THAT(report, Catch::Contains("predicted    3 of 3 inputs") && Catch::Contains("0 skipped"));
  for (const char* f : {"IMG_0001", "IMG_0002", "IMG_0003"}) {
    CHECK(read_ply(cat(out, "/scenes/", f, ".ply")).count() > 0);
    CHECK(fs::exists(cat(out, "/scenes/", f, ".camera.json")));
  }
  REQUIRE(pb_run(base + "--image " + folder + " --out " + out + "/scenes", log) == 0);
  CHECK_THAT(test::read_bytes(log), Catch::Contains("predicted    0 of 3 inputs") && Catch::Contains("3 skipped"));
  fs::remove(out + "/scenes/IMG_0002.camera.json");
  test::write_bytes(out + "/scenes/IMG_0003.ply", "cut short");  // not readable: predicted again
  REQUIRE(pb_run(base + "--image " + folder + " --out " + out + "/scenes", log) == 0);
  CHECK_THAT(test::read_bytes(log), Catch::Contains("predicted    2 of 3 inputs") && Catch::Contains("1 skipped"));
  CHECK(read_ply(out + "/scenes/IMG_0003.ply").count() > 0);

  // A list file: comments, blank lines, paths relative to the list, a repeated stem.
  fs::create_directories(out + "/other");
  fs::copy_file(images + "/IMG_0004.jpg", out + "/other/IMG_0002.jpg");
  test::write_bytes(out + "/list.txt",
                    "# two photos\n\nphotos/IMG_0002.jpg\n  other/IMG_0002.jpg  \n" + images + "/IMG_0005.jpg\n");
  REQUIRE(pb_run(base + "--image " + out + "/list.txt --out " + out + "/listed", log) == 0);
  for (const char* f : {"IMG_0002", "IMG_0002_2", "IMG_0005"}) CHECK(fs::exists(cat(out, "/listed/", f, ".ply")));
  test::write_bytes(out + "/bad.txt", "photos/IMG_0001.jpg\nphotos/none.jpg\n");
  CHECK(pb_run(base + "--image " + out + "/bad.txt --out " + out + "/bad", log) == 1);
  CHECK_THAT(test::read_bytes(log), Catch::Contains("bad.txt: line 2") && Catch::Contains("none.jpg: no such file"));
  // Per-photo data cannot go with many photos.
  CHECK(pb_run(base + "--image " + folder + " --depth x.exr --out " + out + "/depth", log) == 1);
  CHECK_THAT(test::read_bytes(log), Catch::Contains("--depth"));

  // A video: its frames through OpenCV, every frame or every N-th.
  const std::string video = out + "/clip.mp4";
  {
    const cv::Mat first = cv::imread(images + "/IMG_0000.jpg");
    cv::VideoWriter writer(video, cv::VideoWriter::fourcc('m', 'p', '4', 'v'), 10, first.size());
    REQUIRE(writer.isOpened());
    for (int i = 0; i < 5; ++i) writer.write(cv::imread(cat(images, "/IMG_000", i, ".jpg")));
  }
  REQUIRE(pb_run(base + "--image " + video + " --out " + out + "/frames", log) == 0);
  for (int i = 0; i < 5; ++i) CHECK(fs::exists(cat(out, "/frames/frame_00000", i, ".ply")));
  REQUIRE(pb_run(base + "--image " + video + " --every 2 --out " + out + "/every2", log) == 0);
  int64_t every2 = 0;
  for (const auto& e : fs::directory_iterator(out + "/every2")) every2 += e.path().extension() == ".ply";
  CHECK(every2 == 3);  // frames 0, 2, 4
  CHECK(fs::exists(out + "/every2/frame_000004.ply"));

  // --max-gaussians: never more in the output; exactly the limit as supports when the checkpoint's sampler would
  // place more (its fixed 2000 here, and pixel mode's one per pixel at 160x128), so the output comes close to it.
  const std::string pixel_default =
      "--set sampler.mode=pixel --set sampler.edge_supports=false --set "
      "sampler.image_share=0 --set sampler.pixel_floor=0 --set sampler.edge_band=0 ";
  for (const std::string& sampler : {std::string(), std::string("--set sampler.mode=pixel "), pixel_default})
    for (int64_t n : {300, 1000, 1900, 50000}) {
      for (const char* photo : {"IMG_0002.jpg", "IMG_0006.jpg"}) {
        const std::string ply = cat(out, "/max_", n, "_", photo, ".ply");
        REQUIRE(pb_run(base + sampler + "--width 160 --height 128 --max-gaussians " + std::to_string(n) + " --image " +
                           images + "/" + photo + " --out " + ply,
                       log) == 0);
        const std::string text = test::read_bytes(log);
        const int64_t supports = pb_value(text, "supports     "), written = read_ply(ply).count();
        INFO(sampler << " N " << n << " " << photo << ": supports " << supports << ", written " << written);
        CHECK(written <= n);
        CHECK(supports <= n);
        if (n < 1900) {
          CHECK(supports == n);
          CHECK(written >= 0.8 * n);
          CHECK_THAT(text, Catch::Contains("the checkpoint's sampler would place"));
          if (!sampler.empty()) CHECK_THAT(text, Catch::Contains("area sampling places them instead"));
        }
      }
    }
  CHECK(pb_run(base + "--max-gaussians -1 --image " + images + "/IMG_0002.jpg --out " + out + "/neg.ply", log) == 1);
  CHECK_THAT(test::read_bytes(log), Catch::Contains("--max-gaussians -1"));
}
