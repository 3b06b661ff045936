// Config schema: defaults, file loading, base chains, --set overrides, and rejection messages.
#include <catch2/catch.hpp>

#include <filesystem>

#include "core/config.h"
#include "core/error.h"
#include "support/test_util.h"

using namespace isplat;
using test::error_of;

namespace {

struct InnerOptions {
  std::string mode = "area";
  int64_t budget = 1000;
  double scale = 0.5;
  void visit(ConfigVisitor& v) {
    v.field("mode", mode, "placement", {"area", "pixel"});
    v.field("budget", budget, "number of supports", Range::at_least(1));
    v.field("scale", scale, "a unit fraction", Range::unit());
  }
};

struct RootOptions {
  bool flag = false;
  int threads = 0;
  float lr = 5e-5f;
  std::vector<int64_t> hidden = {1024, 256, 64};
  std::vector<std::string> names = {"a"};
  InnerOptions inner;
  void visit(ConfigVisitor& v) {
    v.field("flag", flag, "a switch");
    v.field("threads", threads, "threads", Range::at_least(0));
    v.field("lr", lr, "learning rate", Range::above(0));
    v.field("hidden", hidden, "layer widths", Range::at_least(1));
    v.field("names", names, "labels");
    v.section("inner", "nested options", inner);
  }
};

std::string write_json(const std::string& dir, const std::string& name, const std::string& text) {
  const std::string path = (std::filesystem::path(dir) / name).string();
  test::write_bytes(path, text);
  return path;
}

}  // namespace

TEST_CASE("config: defaults come from the struct", "[config]") {
  auto o = load_config<RootOptions>("");
  CHECK(o.inner.budget == 1000);
  CHECK(o.hidden == std::vector<int64_t>{1024, 256, 64});
  auto j = config_to_json(o);
  CHECK(j["inner"]["mode"] == "area");
  CHECK(j.begin().key() == "flag");  // schema order is kept
}

TEST_CASE("config: file values, base chain and overrides merge in order", "[config]") {
  const auto dir = test::temp_dir("config_merge");
  write_json(dir, "base.json", R"({"threads": 2, "inner": {"budget": 50, "scale": 0.25}})");
  const auto path =
      write_json(dir, "child.json", R"({"base": "base.json", "inner": {"budget": 70}, "hidden": [8, 4]})");
  auto o = load_config<RootOptions>(path, {"inner.mode=pixel", "flag=true", "lr=1e-3", "inner.budget=1.5e3"});
  CHECK(o.threads == 2);           // from base
  CHECK(o.inner.scale == 0.25);    // from base, not overridden
  CHECK(o.inner.budget == 1500);   // --set wins over the file; 1.5e3 is an integer
  CHECK(o.inner.mode == "pixel");  // bare word parsed as a string
  CHECK(o.flag);
  CHECK(o.lr == Approx(1e-3));
  CHECK(o.hidden == std::vector<int64_t>{8, 4});
  // Round trip through JSON gives the same options.
  auto back = config_from_json<RootOptions>(config_to_json(o), "roundtrip");
  CHECK(config_to_json(back) == config_to_json(o));
}

TEST_CASE("config: unknown keys are rejected with file, key and a suggestion", "[config]") {
  const auto dir = test::temp_dir("config_unknown");
  const auto path = write_json(dir, "c.json", R"({"inner": {"budgte": 5}})");
  const auto msg = error_of([&] { load_config<RootOptions>(path); });
  CHECK_THAT(msg, Catch::Contains(path));
  CHECK_THAT(msg, Catch::Contains("unknown key 'inner.budgte'"));
  CHECK_THAT(msg, Catch::Contains("did you mean 'inner.budget'"));
  const auto msg2 = error_of([&] { load_config<RootOptions>("", {"nosuch=1"}); });
  CHECK_THAT(msg2, Catch::Contains("--set nosuch=1"));
  CHECK_THAT(msg2, Catch::Contains("unknown key 'nosuch'"));
}

TEST_CASE("config: wrong types and out-of-range values name the key and the expected form", "[config]") {
  const auto dir = test::temp_dir("config_types");
  const auto p1 = write_json(dir, "a.json", R"({"inner": {"budget": -3}})");
  auto m1 = error_of([&] { load_config<RootOptions>(p1); });
  CHECK_THAT(m1, Catch::Contains(p1));
  CHECK_THAT(m1, Catch::Contains("'inner.budget' must be an integer >= 1"));
  CHECK_THAT(m1, Catch::Contains("got -3"));
  auto m2 = error_of([&] { load_config<RootOptions>("", {"inner.mode=spiral"}); });
  CHECK_THAT(m2, Catch::Contains("must be one of area | pixel"));
  auto m3 = error_of([&] { load_config<RootOptions>("", {"flag=3"}); });
  CHECK_THAT(m3, Catch::Contains("'flag' must be true or false"));
  auto m4 = error_of([&] { load_config<RootOptions>("", {"inner.scale=1.5"}); });
  CHECK_THAT(m4, Catch::Contains("in [0, 1]"));
  auto m5 = error_of([&] { load_config<RootOptions>("", {"threads=2.5"}); });
  CHECK_THAT(m5, Catch::Contains("must be an integer"));
  auto m6 = error_of([&] { load_config<RootOptions>("", {"inner=3"}); });
  CHECK_THAT(m6, Catch::Contains("must be a section"));
  auto m7 = error_of([&] { load_config<RootOptions>("", {"hidden=[4, 0]"}); });
  CHECK_THAT(m7, Catch::Contains("'hidden' must be a list of integers >= 1"));
  auto m8 = error_of([&] { load_config<RootOptions>("", {"lr=0"}); });
  CHECK_THAT(m8, Catch::Contains("> 0"));
  CHECK_THAT(error_of([&] { load_config<RootOptions>("", {"noequals"}); }), Catch::Contains("key.path=value"));
}

TEST_CASE("config: bad files are reported with their path", "[config]") {
  const auto dir = test::temp_dir("config_files");
  CHECK_THAT(error_of([&] { load_config<RootOptions>(dir + "/missing.json"); }), Catch::Contains("no such file"));
  const auto bad = write_json(dir, "bad.json", R"({"threads": 2,)");
  CHECK_THAT(error_of([&] { load_config<RootOptions>(bad); }), Catch::Contains("invalid JSON"));
  const auto loop = write_json(dir, "loop.json", R"({"base": "loop.json"})");
  CHECK_THAT(error_of([&] { load_config<RootOptions>(loop); }), Catch::Contains("loops back"));
}

TEST_CASE("config: reference lists every key with type, default and doc", "[config]") {
  const auto ref = config_reference(RootOptions{});
  CHECK_THAT(ref, Catch::Contains("inner.budget  (int >= 1, default 1000)"));
  CHECK_THAT(ref, Catch::Contains("number of supports"));
  CHECK_THAT(ref, Catch::Contains("inner.mode  (area|pixel, default \"area\")"));
}

namespace {
struct Item {
  std::string name = "x";
  int64_t count = 1;
  void visit(ConfigVisitor& v) {
    v.field("name", name, "item name");
    v.field("count", count, "how many", Range::at_least(0));
  }
};
struct WithList {
  std::vector<Item> items = {Item{"default", 2}};
  void visit(ConfigVisitor& v) { v.list("items", "a list of items", items); }
};
}  // namespace

TEST_CASE("config: lists of sections read, write, validate and document", "[config]") {
  CHECK(load_config<WithList>("").items.at(0).name == "default");
  const auto dir = test::temp_dir("config_list");
  const auto path = write_json(dir, "l.json", R"({"items": [{"name": "a"}, {"name": "b", "count": 5}]})");
  auto o = load_config<WithList>(path);
  REQUIRE(o.items.size() == 2);
  CHECK(o.items[0].count == 1);  // element defaults come from the struct
  CHECK(o.items[1].count == 5);
  CHECK(config_to_json(o)["items"][1]["name"] == "b");
  CHECK(config_from_json<WithList>(config_to_json(o), "x").items.size() == 2);
  const auto bad = write_json(dir, "b.json", R"({"items": [{"name": "a", "cnt": 3}]})");
  CHECK_THAT(error_of([&] { load_config<WithList>(bad); }), Catch::Contains("unknown key 'items[0].cnt'"));
  const auto neg = write_json(dir, "n.json", R"({"items": [{"count": -1}]})");
  CHECK_THAT(error_of([&] { load_config<WithList>(neg); }),
             Catch::Contains("'items[0].count' must be an integer >= 0"));
  CHECK_THAT(error_of([&] { load_config<WithList>("", {"items=3"}); }), Catch::Contains("must be a list of sections"));
  CHECK_THAT(config_reference(WithList{}), Catch::Contains("items[].count  (int >= 0, default 1)"));
}

TEST_CASE("config: --set reaches into list elements by index", "[config]") {
  const auto dir = test::temp_dir("config_list_set");
  const auto path = write_json(dir, "l.json", R"({"items": [{"name": "a"}, {"name": "b"}]})");
  auto o = load_config<WithList>(path, {"items[1].count=7"});
  CHECK(o.items[1].count == 7);
  CHECK(o.items[0].count == 1);
  CHECK_THAT(error_of([&] { load_config<WithList>(path, {"items[5].count=7"}); }), Catch::Contains("has no element 5"));
  CHECK_THAT(error_of([&] { load_config<WithList>(path, {"items[1].cnt=7"}); }),
             Catch::Contains("--set items[1].cnt=7: unknown key 'items[1].cnt'"));
}
