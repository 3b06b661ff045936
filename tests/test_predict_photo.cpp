// The one-photo steps' option checks (src/predict/photo.h) name the options as the CLI's flags or Python's keywords.
#include <catch2/catch.hpp>

#include <cmath>
#include <string>

#include "core/error.h"
#include "predict/photo.h"

using namespace isplat;

namespace predict_photo_test {

// The message check_photo_options throws for `options`, or "" when they pass.
std::string message(const PhotoPredictOptions& options) {
  try {
    check_photo_options(options);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace predict_photo_test

TEST_CASE("predict photo: option names are the CLI's flags or Python's keywords", "[predict]") {
  CHECK(option_name(OptionNames::Flags, "prune_views") == "--prune-views");
  CHECK(option_name(OptionNames::Keywords, "prune_views") == "prune_views");
  CHECK(option_name(OptionNames::Flags, "fx") == "--fx");
}

TEST_CASE("predict photo: the checks before loading anything name the options", "[predict]") {
  using predict_photo_test::message;
  PhotoPredictOptions o;
  CHECK(message(o).empty());  // the defaults pass
  for (const OptionNames names : {OptionNames::Flags, OptionNames::Keywords}) {
    const auto name = [&](const char* key) { return option_name(names, key); };
    PhotoPredictOptions c;
    c.names = names;
    c.intrinsics.cx = 10;
    CHECK_THAT(message(c), Catch::Contains("give " + name("fx") + " too"));
    c.intrinsics.fx = -3;
    CHECK_THAT(message(c), Catch::Contains(name("fx") + " must be a positive focal length"));
    c.intrinsics.fx = 50;
    CHECK(message(c).empty());
    c.intrinsics.hfov = 200;
    CHECK_THAT(message(c), Catch::Contains(name("hfov")));
    c.intrinsics.hfov.reset();
    c.width = 64;
    CHECK_THAT(message(c), Catch::Contains(name("width") + " and " + name("height")) && Catch::Contains("together"));
    c.width = 40, c.height = 32;
    CHECK_THAT(message(c), Catch::Contains(name("width") + " 40") && Catch::Contains("multiples of 16"));
    c.width = 0, c.height = 0;
    c.prune_views = 3;
    CHECK_THAT(message(c), Catch::Contains(name("prune_views")) && Catch::Contains("0, 2, 4 or 6"));
    c.prune_views = 6;
    c.view_floor = 5;
    CHECK_THAT(message(c), Catch::Contains(name("view_floor")));
    c.view_floor = 0;
    c.prune_opacity = std::nan("");
    CHECK_THAT(message(c), Catch::Contains(name("prune_opacity")));
  }
}
