// Training: a tiny configuration's loss falls within a few dozen steps, resuming is bit-exact, and
// repeated non-finite steps stop training with a clear message.
#include <catch2/catch.hpp>

#include <opencv2/imgcodecs.hpp>

#include <torch/torch.h>

#include <filesystem>

#include "core/build_info.h"
#include "core/config.h"
#include "core/error.h"
#include "core/log.h"
#include "io/checkpoint.h"
#include "support/test_util.h"
#include "support/tiny_dataset.h"
#include "support/tiny_model.h"
#include "train/trainer.h"

using namespace isplat;
namespace fs = std::filesystem;

namespace {
std::map<std::string, torch::Tensor> weights(Trainer& t) {
  std::map<std::string, torch::Tensor> w;
  for (const auto& p : t.trainable().named_parameters(true)) w[p.key()] = p.value().detach().clone();
  return w;
}

// A tiny configuration of the depth task (the learned prior at width 8).
TrainConfig tiny_depth_config(const GenerateOptions& data, const std::string& out, int64_t steps) {
  auto cfg = test::tiny_train_config(data, out, steps);
  cfg.task = "depth";
  cfg.model.prior.learned_width = 8;
  return cfg;
}

}  // namespace

TEST_CASE("train: a tiny configuration's training loss falls", "[train]") {
  test::QuietLogs quiet;
  const bool default_model = GENERATE(false, true);
  INFO((default_model ? "the default model (dense head)" : "the paper's layout (implicit decoder)"));
  const auto data = test::make_tiny_dataset("train_falls", 10);
  const std::string dir = test::temp_dir("train_falls_run");
  Trainer trainer(default_model ? test::tiny_train_config(data, dir, 40, test::tiny_default_options())
                                : test::tiny_train_config(data, dir, 40));
  std::vector<double> losses;
  for (int i = 0; i < 40; ++i) losses.push_back(trainer.train_step().losses.at("total"));
  const double first = (losses[0] + losses[1] + losses[2] + losses[3] + losses[4]) / 5;
  const double last = (losses[35] + losses[36] + losses[37] + losses[38] + losses[39]) / 5;
  INFO("mean loss, steps 0-4: " << first << ", steps 35-39: " << last);
  CHECK(last < 0.85 * first);
}

TEST_CASE("train: 2 steps, save, resume, 2 more equals 4 steps straight", "[train]") {
  test::QuietLogs quiet;
  const bool default_model = GENERATE(false, true);
  INFO((default_model ? "the default model (dense head)" : "the paper's layout (implicit decoder)"));
  const auto data = test::make_tiny_dataset("train_resume", 10);
  const std::string a_dir = test::temp_dir("resume_a"), b_dir = test::temp_dir("resume_b");
  const auto config = [&](const std::string& dir) {
    return default_model ? test::tiny_train_config(data, dir, 4, test::tiny_default_options())
                         : test::tiny_train_config(data, dir, 4);
  };
  Trainer straight(config(a_dir));
  for (int i = 0; i < 4; ++i) straight.train_step();
  const std::string ck = b_dir + "/two.safetensors";
  {
    Trainer first(config(b_dir));
    first.train_step();
    first.train_step();
    first.save(ck);
    CHECK(load_checkpoint(ck).step() == 2);
  }
  Trainer resumed(config(b_dir));
  resumed.resume(ck);
  CHECK(resumed.step() == 2);
  resumed.train_step();
  resumed.train_step();
  const auto wa = weights(straight), wb = weights(resumed);
  REQUIRE(wa.size() == wb.size());
  for (const auto& [name, t] : wa) {
    INFO(name);
    CHECK(torch::equal(t, wb.at(name)));  // bit-identical
  }
  // A checkpoint for the other task is refused with a message.
  auto depth_cfg = test::tiny_train_config(data, test::temp_dir("resume_depth"), 4);  // b_dir is locked by `resumed`
  depth_cfg.task = "depth";
  Trainer depth(depth_cfg);
  CHECK_THROWS_WITH(depth.resume(ck), Catch::Contains("checkpoint is for task 'gaussians'"));
  // Nor does a run resume into another model: a changed sampler key is named.
  auto other = config(test::temp_dir("resume_other"));
  other.model.sampler.image_share = 0.25;
  Trainer changed(other);
  CHECK_THROWS_WITH(changed.resume(ck), Catch::Contains("model/sampler/image_share differ"));
}

TEST_CASE("train: repeated non-finite losses stop training with a clear message", "[train]") {
  test::QuietLogs quiet;
  const auto data = test::make_tiny_dataset("train_nan", 8);
  auto cfg = test::tiny_train_config(data, test::temp_dir("train_nan_run"), 10);
  cfg.train.max_bad_steps = 2;
  Trainer trainer(cfg);
  {
    torch::NoGradGuard g;
    trainer.trainable().named_parameters()["decoder.head.bias"].fill_(std::numeric_limits<float>::quiet_NaN());
  }
  const StepStats s = trainer.train_step();
  CHECK(s.skipped);
  CHECK_THROWS_WITH(trainer.train_step(), Catch::Contains("2 consecutive non-finite steps"));
}

TEST_CASE("train: the depth task trains the learned prior", "[train]") {
  test::QuietLogs quiet;
  const auto data = test::make_tiny_dataset("train_depth", 8);
  auto cfg = tiny_depth_config(data, test::temp_dir("train_depth_run"), 30);
  cfg.data.batch_size = 2;
  cfg.optim.lr = 5e-3;
  Trainer trainer(cfg);
  std::vector<double> l;
  for (int i = 0; i < 30; ++i) l.push_back(trainer.train_step().losses.at("total"));
  CHECK((l[25] + l[26] + l[27] + l[28] + l[29]) < 0.8 * (l[0] + l[1] + l[2] + l[3] + l[4]));
}

TEST_CASE("train: data.extra_roots trains on a second release folder too, and a missing one is named", "[train]") {
  test::QuietLogs quiet;
  const auto rooms = test::make_tiny_dataset("train_roots_rooms", 6);
  const auto clutter = test::style_dataset_options(test::temp_dir("train_roots_clutter"), 6, {"clutter"}, 2);
  generate_datasets(clutter);
  auto cfg = test::tiny_train_config(rooms, test::temp_dir("train_roots_run"), 2);
  const auto alone = read_training_sequences(cfg.data, "train");
  const auto alone_val = read_training_sequences(cfg.data, "val");
  REQUIRE_FALSE(alone.empty());
  cfg.data.extra_roots = {generated_hypersim_root(clutter.out)};
  const auto both = read_training_sequences(cfg.data, "train");
  REQUIRE(both.size() == alone.size() + 2);  // two clutter scenes, one camera each
  for (size_t i = 0; i < alone.size(); ++i) CHECK(both[i].frames.at(0).image_path == alone[i].frames.at(0).image_path);
  for (size_t i = alone.size(); i < both.size(); ++i)
    CHECK(both[i].frames.at(0).image_path.rfind(generated_hypersim_root(clutter.out), 0) == 0);
  CHECK(read_training_sequences(cfg.data, "val").size() == alone_val.size());  // the extra folder has no val scenes
  Trainer trainer(cfg);                                                        // trains on both
  CHECK(std::isfinite(trainer.train_step().losses.at("total")));
  cfg.data.extra_roots = {clutter.out + "/nope"};
  CHECK_THROWS_WITH(read_training_sequences(cfg.data, "train"),
                    Catch::Contains("nope: no such folder (config key data.extra_roots)"));
}

TEST_CASE("train: augmentation changes training tuples, never validation", "[train][augment]") {
  test::QuietLogs quiet;
  const auto data = test::make_tiny_dataset("train_augment", 8);
  const auto plain = tiny_depth_config(data, test::temp_dir("train_augment_plain"), 2);
  auto aug = plain;
  aug.train.out = test::temp_dir("train_augment_aug");
  aug.data.tuples.augment.flip = 1.0;
  aug.data.tuples.augment.brightness = 0.5;
  Trainer a(plain), b(aug);
  CHECK(a.validate(false) == b.validate(false));  // same weights, same validation tuples
  CHECK(a.train_step().losses.at("total") != b.train_step().losses.at("total"));
}

TEST_CASE("train: run() keeps init, last, best and the last K periodic checkpoints, and --resume auto continues",
          "[train]") {
  test::QuietLogs quiet;
  const auto data = test::make_tiny_dataset("train_run", 8);
  const std::string out = test::temp_dir("train_run_out");
  auto cfg = test::tiny_train_config(data, out, 4);
  cfg.train.checkpoint_every = 1;
  cfg.train.val_every = 2;
  cfg.train.keep_last = 2;
  cfg.train.val_images = 1;
  {
    Trainer t(cfg);
    CHECK(t.run() == 0);
  }
  const fs::path ck = fs::path(out) / "checkpoints";
  for (const char* f : {"init.safetensors", "last.safetensors", "best.safetensors", "step_000003.safetensors",
                        "step_000004.safetensors"})
    CHECK(fs::exists(ck / f));
  CHECK_FALSE(fs::exists(ck / "step_000002.safetensors"));          // only the last 2 periodic ones stay
  CHECK(fs::hard_link_count(ck / "step_000004.safetensors") == 1);  // last is its own file: damage stays local
  CHECK(load_checkpoint((ck / "last.safetensors").string()).step() == 4);
  CHECK(load_checkpoint((ck / "init.safetensors").string()).tensors.count("optim/state") == 0);
  CHECK(fs::exists(fs::path(out) / "train_log.jsonl"));
  CHECK(fs::exists(fs::path(out) / "summary.json"));
  CHECK(read_json_file((fs::path(out) / "summary.json").string()).value("commit", "") == build_commit());
  bool panel = false;
  for (const auto& e : fs::directory_iterator(fs::path(out) / "val")) panel |= e.path().extension() == ".png";
  CHECK(panel);
  // curves.png: four charts (loss terms, lr, validation PSNR, validation loss) refreshed at each validation.
  const cv::Mat curves = cv::imread((fs::path(out) / "curves.png").string());
  REQUIRE_FALSE(curves.empty());
  CHECK(curves.cols == 2 * 640);
  CHECK(curves.rows == 2 * 420);
  cfg.train.steps = 6;
  {
    Trainer more(cfg);
    more.resume("auto");
    CHECK(more.step() == 4);
    CHECK(more.run() == 0);
  }
  CHECK(load_checkpoint((ck / "last.safetensors").string()).step() == 6);
  Trainer fresh(cfg);  // the folder's lock was released with `more`
  CHECK_THROWS_WITH(fresh.resume((ck / "init.safetensors").string()), Catch::Contains("holds no optimizer state"));
}
