// The weights lookup: an explicit path as given, then $INFINISPLAT_WEIGHTS, the checkout's weights/, the user cache.
#include <catch2/catch.hpp>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "core/weights.h"
#include "prior/depth_prior.h"
#include "support/test_util.h"

using namespace isplat;
namespace fs = std::filesystem;

TEST_CASE("weights: a file name is looked up in order, a path is taken as given", "[weights][core]") {
  const std::string root = test::temp_dir("weights_lookup");
  const fs::path env_dir = fs::path(root) / "env", home = fs::path(root) / "home";
  const fs::path cache = home / ".cache" / "infinisplat" / "weights";
  fs::create_directories(env_dir);
  fs::create_directories(cache);
  test::write_bytes((cache / "a.safetensors").string(), "cache");
  test::write_bytes((cache / "b.safetensors").string(), "cache");
  test::write_bytes((env_dir / "a.safetensors").string(), "env");
  test::ScopedEnv e(kWeightsEnv, env_dir.string().c_str()), h("HOME", home.string().c_str());

  const auto path = weights_search_path();
  REQUIRE(path.size() >= 2);
  CHECK(path.front() == env_dir.string());  // the environment first, the user cache last
  CHECK(path.back() == cache.string());
  CHECK(find_weights_file("a.safetensors") == (env_dir / "a.safetensors").string());
  CHECK(find_weights_file("b.safetensors") == (cache / "b.safetensors").string());
  CHECK(find_weights_file("weights/b.safetensors") == (cache / "b.safetensors").string());  // the old shipped form
  CHECK(find_weights_file("missing.safetensors").empty());
  const std::string explicit_path = (fs::path(root) / "nowhere" / "a.safetensors").string();
  CHECK(find_weights_file(explicit_path) == explicit_path);  // as given, even when missing: the caller names it
  CHECK(find_weights_folder({"a.safetensors", "b.safetensors"}) == cache.string());  // the first holding both
  CHECK(find_weights_folder({"a.safetensors", "missing.safetensors"}).empty());
  CHECK_THAT(missing_weights_hint(), Catch::Contains(env_dir.string()) && Catch::Contains(kGetWeightsCommand));
}

TEST_CASE("weights: a missing depth model named by file is an error that says where it was looked for",
          "[weights][prior]") {
  const std::string root = test::temp_dir("weights_torchscript");
  test::ScopedEnv e(kWeightsEnv, root.c_str());
  PriorOptions o;
  o.type = "torchscript";
  o.torchscript = "depth_pro_traced.pt";
  CHECK_THAT(test::error_of([&] { make_depth_prior(o); }),
             Catch::Contains("depth_pro_traced.pt: no such file (prior.torchscript") && Catch::Contains(root));
}
