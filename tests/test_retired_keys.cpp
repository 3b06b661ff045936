// Retired config keys: a stored config holding one at its kept value loads as before; another value is refused by
// name, value and study; the schema itself no longer knows any of them.
#include <catch2/catch.hpp>

#include "core/config.h"
#include "core/error.h"
#include "core/retired_keys.h"
#include "model/infinisplat.h"
#include "train/train_config.h"

using namespace isplat;

TEST_CASE("retired keys: kept values are stripped silently, removed values are refused with their study",
          "[config][retired]") {
  nlohmann::json model = {
      {"sampler", {{"fill_mode", "blend"}, {"fill_far_width", 6}, {"edge_scale", 1}, {"fill_px", 4}}}};
  strip_retired_keys(model, "old.ckpt");
  CHECK(model == nlohmann::json{{"sampler", {{"fill_px", 4}}}});
  const ModelOptions o = config_from_json<ModelOptions>(model, "old.ckpt");
  CHECK(o.sampler.fill_px == 4);

  nlohmann::json far = {{"sampler", {{"fill_mode", "far"}}}};
  CHECK_THROWS_WITH(strip_retired_keys(far, "old.ckpt (stored config)"),
                    Catch::Contains("old.ckpt (stored config)") && Catch::Contains("model.sampler.fill_mode") &&
                        Catch::Contains("\"far\"") && Catch::Contains("2026-11-27-fill-far"));
  nlohmann::json scaled = {{"sampler", {{"edge_scale", 0.5}}}};
  CHECK_THROWS_WITH(strip_retired_keys(scaled, "run"), Catch::Contains("model.sampler.edge_scale = 0.5"));

  // A whole stored config: the model section's keys by their full path; other sections untouched.
  nlohmann::json config = {{"model", {{"sampler", {{"placement", "random"}, {"color", "bilinear"}}}}},
                           {"train", {{"steps", 3}}}};
  strip_retired_config_keys(config, "config.json");
  CHECK(config == nlohmann::json{{"model", {{"sampler", nlohmann::json::object()}}}, {"train", {{"steps", 3}}}});
  // A section: its listed keys at their kept values (others did nothing without them).
  nlohmann::json calm = {{"train", {{"depth_error", {{"scale_sigma", 0}, {"warp_cells", 5}}}}}};
  strip_retired_config_keys(calm, "config.json");
  CHECK(calm == nlohmann::json{{"train", nlohmann::json::object()}});
  nlohmann::json noisy = {{"train", {{"depth_error", {{"scale_sigma", 0.3}}}}}};
  CHECK_THROWS_WITH(strip_retired_config_keys(noisy, "config.json"),
                    Catch::Contains("train.depth_error") && Catch::Contains("2026-11-26-depth-error"));
  nlohmann::json model_only = {{"train", {{"depth_error", {{"scale_sigma", 0.3}}}}}};
  CHECK_NOTHROW(strip_retired_keys(model_only, "x"));  // the model section's keys only
  nlohmann::json not_object = "x";
  CHECK_NOTHROW(strip_retired_keys(not_object, "x"));
}

TEST_CASE("retired keys: the schema knows none of them, and each kept value loads once stripped", "[config][retired]") {
  for (const RetiredKey& k : retired_keys()) {
    INFO(k.path);
    CHECK_FALSE(k.study.empty());
    // The key as a stored config holds it, at its kept value (or any value where none is kept).
    nlohmann::json config = nlohmann::json::object();
    nlohmann::json* at = &config;
    std::string rest = k.path;
    for (size_t dot; (dot = rest.find('.')) != std::string::npos; rest = rest.substr(dot + 1))
      at = &(*at)[rest.substr(0, dot)];
    (*at)[rest] = k.kept.is_null() ? nlohmann::json(1) : k.kept;
    CHECK_THROWS_WITH(config_from_json<TrainConfig>(config, "stored"),
                      Catch::Contains("was retired") && Catch::Contains(k.study));
    strip_retired_config_keys(config, "stored");
    CHECK_NOTHROW(config_from_json<TrainConfig>(config, "stored"));
  }
}
