// Every shipped config parses against its schema, so configs cannot rot as options change.
#include <catch2/catch.hpp>

#include <filesystem>

#include "core/config.h"
#include "eval/eval_config.h"
#include "train/train_config.h"

using namespace isplat;
namespace fs = std::filesystem;

TEST_CASE("configs: every file in configs/ is valid for its executable", "[config][configs]") {
  int checked = 0;
  for (const auto& e : fs::recursive_directory_iterator(fs::path(ISPLAT_SOURCE_DIR) / "configs")) {
    if (e.path().extension() != ".json") continue;
    const std::string path = e.path().string();
    INFO(path);
    if (e.path().filename().string().rfind("eval_", 0) == 0) {
      const auto c = load_config<EvalConfig>(path);
      CHECK_FALSE(c.datasets.empty());
    } else {
      const auto c = load_config<TrainConfig>(path);
      CHECK(c.train.steps > 0);
    }
    ++checked;
  }
  CHECK(checked >= 12);
  const auto rgb = load_config<TrainConfig>(std::string(ISPLAT_SOURCE_DIR) + "/configs/hypersim_rgb.json");
  CHECK(rgb.model.sampler.budget == 1500000);  // paper settings
  CHECK(rgb.model.encoder.vit.size == "L");
  CHECK(rgb.optim.lr == 5e-5);
  const auto lidar = load_config<TrainConfig>(std::string(ISPLAT_SOURCE_DIR) + "/configs/hypersim_lidar.json");
  CHECK(lidar.model.prior.type == "sparse");
  CHECK(lidar.model.prior.sparse.prompts == 1500);
  CHECK(lidar.model.encoder.vit.size == "L");  // inherited from the RGB config
}
