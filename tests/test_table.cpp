// The report table writer (io/table.h).
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>

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
