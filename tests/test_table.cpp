// The report table writer (io/table.h) and the results log's method fields (eval/results_log.h).
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>

#include "eval/results_log.h"
#include "io/atomic_file.h"
#include "io/table.h"
#include "support/test_util.h"

using namespace isplat;
namespace fs = std::filesystem;

TEST_CASE("table: one declaration of the columns, written as Markdown, CSV and JSON", "[io][report]") {
  Table t;
  t.columns = {{"method"}, {"pairs"}, {"psnr", 2, "PSNR"}, {"value", -1}, {"note"}};
  t.add({"lift", int64_t{3}, 21.456, 0.02, TableCell()});
  t.add({"a,b", int64_t{0}, std::nan(""), 1500.0, "x"});
  CHECK_THROWS_WITH(t.add({"short"}), Catch::Contains("1 cells for 5 columns"));
  CHECK(table_markdown(t) ==
        "| method | pairs | PSNR | value | note |\n|---|---|---|---|---|\n| lift | 3 | 21.46 | 0.02 | - |\n"
        "| a,b | 0 | n/a | 1500 | x |\n");
  CHECK(format_csv(table_csv(t)) == "method,pairs,psnr,value,note\nlift,3,21.46,0.02,\n\"a,b\",0,n/a,1500,x\n");
  const auto js = table_json(t);
  REQUIRE(js.size() == 2);
  CHECK(js[0]["psnr"].get<double>() == 21.456);  // every digit
  CHECK(js[0]["note"].is_null());
  CHECK(js[1]["psnr"].is_null());  // not measured
  CHECK(js[1]["pairs"].get<int64_t>() == 0);
  CHECK(js[0].begin().key() == "method");  // the columns' order
  CHECK(format_fixed(std::numeric_limits<double>::infinity(), 2) == "n/a");
}

TEST_CASE("results log: the method and its sweep point are fields of every record", "[eval][report]") {
  const std::string path = test::temp_dir("results_fields") + "/results_full_depth_noise0_02.jsonl";
  const MethodId noise{"full", {"perturb.depth_noise", "", 0.02}};
  PairResult r;
  r.index = 0, r.psnr = 20, r.ssim = 0.5, r.mask_fraction = 0.5;
  {
    ResultsLog log(path, nullptr, noise);
    log.append(r);
  }
  auto j = nlohmann::json::parse(test::read_bytes(path));
  CHECK(j["method"] == "full");
  CHECK(j["sweep_key"] == "perturb.depth_noise");
  CHECK(j["sweep_value"].get<double>() == 0.02);
  CHECK_FALSE(j.contains("budget"));
  CHECK(result_from_json(j).method == noise);
  // A log written before the fields (found by the same generated file name) is the file's method: it resumes.
  for (const char* k : {"method", "sweep_key", "sweep_value"}) j.erase(k);
  write_file_atomic(path, j.dump() + "\n");
  {
    const ResultsLog old(path, nullptr, noise);
    REQUIRE(old.done().count(0) == 1);
    CHECK(old.done().at(0).method == noise);
  }
  // A record of another sweep point is never taken for this one: that pair is scored again.
  PairResult other = r;
  other.index = 1;
  other.method = {"full", {"perturb.depth_noise", "", 0.05}};
  write_file_atomic(path, j.dump() + "\n" + result_json(other).dump() + "\n");
  test::QuietLogs quiet;
  const ResultsLog mixed(path, nullptr, noise);
  CHECK(mixed.done().size() == 1);
  CHECK(mixed.done().count(1) == 0);
}
