// Old checkpoints keep scoring as they did: a checkpoint written before the model's defaults became the recipe
// (tests/fixtures/checkpoint_v1, written by the code of that time) predicts the Gaussians it predicted then.
#include <catch2/catch.hpp>

#include <torch/torch.h>

#include <filesystem>

#include "core/config.h"
#include "geometry/camera_torch.h"
#include "io/checkpoint.h"
#include "io/safetensors.h"
#include "model/model_io.h"
#include "support/test_util.h"
#include "support/tiny_model.h"
#include "train/train_config.h"

using namespace isplat;
namespace fs = std::filesystem;

namespace {
const fs::path kFixture = fs::path(ISPLAT_SOURCE_DIR) / "tests" / "fixtures" / "checkpoint_v1";

// The fixture's input: a wall with a box in front, a textured image, fixed by seed.
std::map<std::string, torch::Tensor> fixture_input() {
  const int64_t H = 32, W = 48;
  torch::manual_seed(11);
  auto depth = torch::full({H, W}, 3.0f);
  depth.narrow(1, 10, 14).narrow(0, 8, 16).fill_(1.5f);
  return {{"input/image", torch::rand({3, H, W})},
          {"input/depth", depth},
          {"input/valid", torch::ones({H, W})},
          {"input/K", make_K(40, 40, W / 2.0, H / 2.0)},
          {"input/T_cw", torch::eye(4)}};
}

Gaussians predict(const std::string& checkpoint, const std::map<std::string, torch::Tensor>& in) {
  auto pipeline = load_pipeline(checkpoint);
  return pipeline->model()
      ->predict(in.at("input/image"), in.at("input/K"), in.at("input/T_cw"), in.at("input/depth"), in.at("input/valid"),
                3)
      .gaussians;
}
}  // namespace

// Run once, by hand, at the commit before the defaults changed (e8a194c + the weights lookup):
//   build/infinisplat_tests "[.write_checkpoint_v1]"
TEST_CASE("checkpoint versions: write the v1 fixture", "[.write_checkpoint_v1]") {
  fs::create_directories(kFixture);
  torch::manual_seed(7);
  TrainConfig config;
  config.model = test::tiny_model_options(900, 1);
  config.model.prior.type = "dataset";
  InfiniSplat model(config.model);
  {
    torch::NoGradGuard g;
    model->decoder->head->weight.normal_(0, 0.2);  // nonzero updates, so the decoder's output counts
    model->decoder->head->bias.normal_(0, 0.2);
  }
  Checkpoint ck;
  put_module(ck, *model);
  ck.metadata["step"] = "0";
  ck.metadata["task"] = "gaussians";
  ck.metadata["config"] = config_to_json(config).dump();
  save_checkpoint((kFixture / "full_config.safetensors").string(), ck);
  auto expected = fixture_input();
  const Gaussians g = predict((kFixture / "full_config.safetensors").string(), expected);
  expected["expected/means"] = g.means, expected["expected/scales"] = g.scales, expected["expected/quats"] = g.quats;
  expected["expected/colors"] = g.colors, expected["expected/opacities"] = g.opacities;
  write_safetensors((kFixture / "expected.safetensors").string(), expected,
                    {{"cpu_capability", test::aten_capability()}});
  CHECK(g.count() > 0);
}

TEST_CASE("checkpoint versions: a v1 checkpoint predicts the Gaussians it predicted when it was written",
          "[checkpoint][model]") {
  const SafeTensors expected = read_safetensors((kFixture / "expected.safetensors").string());
  // Bit for bit where the CPU runs the same vector kernels as the machine that wrote the fixture; elsewhere
  // LibTorch's exp/erf kernels may differ in the last bit, so within 1e-5.
  const bool same_kernels = expected.metadata.at("cpu_capability") == test::aten_capability();
  const std::string full = (kFixture / "full_config.safetensors").string();
  Checkpoint ck = load_checkpoint(full);
  CHECK(ck.metadata.count("config_version") == 0);  // written before versions existed
  // The same checkpoint as one from before the sampler's edge keys and the composer's orientation existed.
  auto json = nlohmann::json::parse(ck.config_json());
  for (const char* key : {"budget_mode", "density", "edge_supports", "image_share", "pixel_floor", "edge_behind",
                          "edge_shift", "edge_band", "edge_band_at"})
    REQUIRE(json["model"]["sampler"].erase(key) == 1);
  REQUIRE(json["model"]["composer"].erase("orientation") == 1);
  ck.metadata["config"] = json.dump();
  const std::string older = test::temp_dir("checkpoint_v1") + "/older_config.safetensors";
  save_checkpoint(older, ck);
  for (const std::string& file : {full, older}) {
    INFO(file);
    const Gaussians g = predict(file, expected.tensors);
    const std::map<std::string, torch::Tensor> got = {
        {"means", g.means}, {"scales", g.scales}, {"quats", g.quats}, {"colors", g.colors}, {"opacities", g.opacities}};
    for (const auto& [name, t] : got) {
      INFO(name);
      const auto& want = expected.tensors.at("expected/" + name);
      REQUIRE(t.sizes() == want.sizes());
      if (same_kernels)
        CHECK(torch::equal(t, want));
      else
        CHECK(torch::allclose(t, want, 1e-5, 1e-6));
    }
  }
}

TEST_CASE("checkpoint versions: a stored config without the sampler and decoder keys takes its version's defaults",
          "[checkpoint][model]") {
  Checkpoint ck;
  ck.metadata["config"] = R"({"model": {"encoder": {"dino": false}}})";
  const auto options = [&](const char* version) {
    ck.metadata["config_version"] = version;
    return model_options_from_checkpoint(ck, "ck.safetensors");
  };
  const ModelOptions v2 = options("2"), v3 = options("3");
  CHECK(v2.sampler.mode == "area");  // 2026-12-06 to 2026-12-07: area sampling, edge supports, implicit decoder
  CHECK(v2.sampler.edge_supports);
  CHECK(v2.sampler.edge_band == 2);
  CHECK(v2.decoder.mode == "implicit");
  CHECK(v3.sampler.mode == "pixel");  // since: pixel centres and silhouettes, the dense head
  CHECK(v3.sampler.edge_behind == 3);
  CHECK(v3.decoder.mode == "dense");
  const auto now = config_to_json(ModelOptions{}), stored = config_to_json(v3);
  CHECK(stored["sampler"] == now["sampler"]);
  CHECK(stored["decoder"] == now["decoder"]);
  CHECK_FALSE(v2.encoder.dino);  // a stored key keeps its value
  CHECK_THROWS_WITH(options("4"), Catch::Contains("ck.safetensors: config_version '4' is not one this build knows"));
}
