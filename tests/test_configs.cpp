// Every shipped config parses against its schema, so configs cannot rot as options change.
#include <catch2/catch.hpp>

#include <filesystem>

#include "core/config.h"
#include "data/synth/generate.h"
#include "eval/depth_eval.h"
#include "eval/eval_config.h"
#include "experiment/experiment.h"
#include "model/model_io.h"
#include "train/train_config.h"

using namespace isplat;
namespace fs = std::filesystem;

TEST_CASE("configs: every file in configs/ is valid for its executable", "[config][configs]") {
  int checked = 0;
  for (const auto& e : fs::recursive_directory_iterator(fs::path(ISPLAT_SOURCE_DIR) / "configs")) {
    if (e.path().extension() != ".json") continue;
    const std::string path = e.path().string();
    INFO(path);
    const std::string name = e.path().filename().string();
    const bool recipe = e.path().parent_path().filename() == "recipe";  // configs/recipe: the ablation table
    if (name.rfind("depth_eval", 0) == 0) {
      const auto c = load_config<DepthEvalConfig>(path);
      CHECK_FALSE(c.priors.empty());
    } else if (name.rfind("eval", 0) == 0) {
      const auto c = load_config<EvalConfig>(path);
      CHECK_FALSE(c.datasets.empty());
      CHECK_NOTHROW(check_dataset_names(c.datasets));
      CHECK_NOTHROW(expand_sweeps(c.methods));  // budgets and sweeps expand, and no two methods share a results file
    } else if (name.rfind("data", 0) == 0) {    // data.json, data_hall.json: generator configs
      const auto c = load_config<GenerateConfig>(path);
      CHECK(c.generate.train_scenes + static_cast<int64_t>(c.generate.eval_datasets.size()) > 0);  // writes something
    } else if (recipe && name.rfind("ablation", 0) == 0) {
      const auto c = load_config<ExperimentConfig>(path);
      CHECK_FALSE(c.rows.empty());
      CHECK_NOTHROW(Experiment(c));  // rows, reuse and the reference are consistent
      auto local = c;                // every row's keys are valid for the recipe (paths are relative to the project)
      local.train_config = (fs::path(ISPLAT_SOURCE_DIR) / c.train_config).string();
      const Experiment e(local);
      for (const auto& r : local.rows)
        for (const auto& run : e.runs(r)) {
          INFO(r.name);
          CHECK_NOTHROW(e.run_config(run));
        }
    } else {
      const auto c = load_config<TrainConfig>(path);
      CHECK(c.train.steps > 0);
    }
    ++checked;
  }
  CHECK(checked >= 22);  // 9 user configs, 7 ablations, 6 in configs/recipe (the lab keeps the rest)
  const auto rgb = load_config<TrainConfig>(std::string(ISPLAT_SOURCE_DIR) + "/configs/hypersim_rgb.json");
  CHECK(rgb.model.sampler.mode == "area");  // the paper's settings: its method, at its budget
  CHECK(rgb.model.decoder.mode == "implicit");
  CHECK(rgb.model.sampler.budget == 1500000);
  CHECK(rgb.model.encoder.vit.size == "L");
  CHECK(rgb.optim.lr == 5e-5);
  const auto lidar = load_config<TrainConfig>(std::string(ISPLAT_SOURCE_DIR) + "/configs/hypersim_lidar.json");
  CHECK(lidar.model.prior.type == "sparse");
  CHECK(lidar.model.prior.sparse.prompts == 1500);
  CHECK(lidar.model.encoder.vit.size == "L");  // inherited from the RGB config
  // The paper's method at the demo's and the lab's scale is version 2's model, every key pinned; the default model
  // is the defaults.
  const ModelOptions v2 = model_defaults(2), now;
  for (const char* name : {"quickstart_paper.json", "recipe/paper.json", "quickstart.json", "recipe/recipe.json"}) {
    INFO(name);
    const auto c = load_config<TrainConfig>(std::string(ISPLAT_SOURCE_DIR) + "/configs/" + name);
    const bool paper = std::string(name).find("paper") != std::string::npos;
    CHECK(config_to_json(c.model.sampler) == config_to_json(paper ? v2.sampler : now.sampler));
    CHECK(c.model.decoder.mode == (paper ? "implicit" : "dense"));
    CHECK(c.model.composer.orientation == "surface");
    CHECK(c.model.composer.scale_floor_px == 0.35);
  }
}
