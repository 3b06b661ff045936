// Core utilities: argument parsing, progress formatting, thread configuration and the runtime report.
#include <catch2/catch.hpp>

#include <ATen/Parallel.h>
#include <c10/core/CPUAllocator.h>
#include <torch/torch.h>

#include <cstdlib>
#include <filesystem>

#include "core/args.h"
#include "core/build_info.h"
#include "core/error.h"
#include "core/progress.h"
#include "core/runtime.h"
#include "core/tensor_memory.h"
#include "support/test_util.h"

using namespace isplat;

TEST_CASE("args: options, flags, repeated values and errors", "[core]") {
  std::string config;
  int64_t n = 3;
  double x = 0;
  bool verbose = false;
  std::vector<std::string> sets;
  std::string input;
  ArgParser p("prog", "test program");
  p.option("--config", config, "config");
  p.option("--n", n, "count");
  p.option("--x", x, "value");
  p.flag("--verbose", verbose, "talk");
  p.repeated("--set", sets, "override");
  p.positional("input", input, "input file");
  const char* argv[] = {"prog", "in.png", "--config", "a.json",    "--n=7", "--set",
                        "a=1",  "--set",  "b=2",      "--verbose", "--x",   "0.5"};
  REQUIRE(p.parse(12, const_cast<char**>(argv)));
  CHECK(input == "in.png");
  CHECK(config == "a.json");
  CHECK(n == 7);
  CHECK(x == 0.5);
  CHECK(verbose);
  CHECK(sets == std::vector<std::string>{"a=1", "b=2"});
  const char* bad[] = {"prog", "in", "--nope"};
  CHECK_THROWS_WITH(p.parse(3, const_cast<char**>(bad)), Catch::Contains("unknown option '--nope'"));
  const char* badnum[] = {"prog", "in", "--n", "seven"};
  CHECK_THROWS_WITH(p.parse(4, const_cast<char**>(badnum)), Catch::Contains("expected an integer, got 'seven'"));
  const char* missing[] = {"prog"};
  CHECK_THROWS_WITH(p.parse(1, const_cast<char**>(missing)), Catch::Contains("missing argument <input>"));
  CHECK_THAT(p.help(), Catch::Contains("--set KEY=VALUE") || Catch::Contains("--set VALUE"));
}

TEST_CASE("progress: durations and status line", "[core]") {
  CHECK(ProgressBar::format_duration(4.2) == "0:04");
  CHECK(ProgressBar::format_duration(187) == "3:07");
  CHECK(ProgressBar::format_duration(3909) == "1:05:09");
  ProgressBar bar("train", 100, "step");
  bar.set(25);
  bar.postfix("loss 0.5");
  const auto line = bar.status_line();
  CHECK_THAT(line, Catch::Contains("25/100 25%"));
  CHECK_THAT(line, Catch::Contains("ETA"));
  CHECK_THAT(line, Catch::Contains("| loss 0.5"));
  bar.finish();
}

TEST_CASE("runtime: threads default to all cores, report names LibTorch and BLAS", "[core]") {
  const int all = configure_threads(0);
  CHECK(all == static_cast<int>(std::max(1u, std::thread::hardware_concurrency())));
  CHECK(configure_threads(1) == 1);
  CHECK(at::get_num_threads() == 1);
  configure_threads(0);
  const auto report = runtime_report(false);
  CHECK_THAT(report, Catch::Contains("LibTorch        1.13"));
  CHECK_THAT(report, Catch::Contains("OpenMP          yes"));
  // The build's commit: 12 hex digits (with -dirty for uncommitted changes), or unknown outside a git checkout.
  const std::string commit = build_commit();
  CHECK_THAT(report, Catch::Contains("(commit " + commit + ")"));
  const bool hex12 = commit.size() >= 12 && commit.find_first_not_of("0123456789abcdef") >= 12;
  CHECK((commit == "unknown" || (hex12 && (commit.size() == 12 || commit.substr(12) == "-dirty"))));
  CHECK_THAT(loaded_blas(), Catch::Contains("blas"));
}

TEST_CASE("start-up: executables shorten OpenMP's idle spin, unless the user chose how workers wait", "[core]") {
  // core/startup.cpp re-executes the program with GOMP_SPINCOUNT=3000 before libgomp reads its environment.
  const std::string tool = (std::filesystem::path(ISPLAT_BINARY_DIR) / "infinisplat").string();
  const std::string out = test::temp_dir("startup_wait") + "/version.txt";
  auto report = [&](const std::string& env) {
    const std::string cmd =
        "env -u OMP_WAIT_POLICY -u GOMP_SPINCOUNT " + env + " " + tool + " version --no-bench > " + out + " 2>&1";
    REQUIRE(std::system(cmd.c_str()) == 0);
    return test::read_bytes(out);
  };
  CHECK_THAT(report(""), Catch::Contains("OpenMP wait     OMP_WAIT_POLICY=(unset) GOMP_SPINCOUNT=3000 ("));
  CHECK_THAT(report("OMP_WAIT_POLICY=passive"),
             Catch::Contains("OpenMP wait     OMP_WAIT_POLICY=passive GOMP_SPINCOUNT=(unset) ("));
  CHECK_THAT(report("GOMP_SPINCOUNT=300000"),
             Catch::Contains("OpenMP wait     OMP_WAIT_POLICY=(unset) GOMP_SPINCOUNT=300000 ("));
  // This test program links the same start-up, so it runs with a choice too.
  CHECK((std::getenv("OMP_WAIT_POLICY") != nullptr || std::getenv("GOMP_SPINCOUNT") != nullptr));
}

TEST_CASE("tensor memory: the test binary counts from its first tensor on, as infinisplat-eval does", "[core]") {
  // catch_main.cpp installs the counting allocator first thing (ctest runs each case in a fresh process).
  CHECK(tensor_memory_counted());
  CHECK(c10::GetCPUAllocator() != c10::GetDefaultCPUAllocator());
  const int64_t before = live_tensor_bytes();
  const torch::Tensor t = torch::empty({256});
  CHECK(live_tensor_bytes() == before + 1024);
}

TEST_CASE("tensor memory: live CPU tensor bytes and their peak, exactly", "[core]") {
  count_tensor_memory();
  count_tensor_memory();  // idempotent
  REQUIRE(tensor_memory_counted());
  const int64_t live0 = live_tensor_bytes();
  reset_tensor_peak();
  CHECK(peak_tensor_bytes() == live0);
  {
    torch::Tensor a = torch::ones({1000, 250});  // 1,000,000 bytes
    CHECK(live_tensor_bytes() == live0 + 1000000);
    torch::Tensor b = a + 1;  // a second block of the same size while the first is live
    CHECK(live_tensor_bytes() == live0 + 2000000);
    CHECK(peak_tensor_bytes() >= live0 + 2000000);  // plus the add's few bytes of scalar temporaries
    CHECK(peak_tensor_bytes() < live0 + 2000000 + 1024);
    CHECK(reinterpret_cast<uintptr_t>(b.data_ptr()) % 64 == 0);  // as aligned as c10's own blocks
    CHECK(b.data_ptr<float>()[249999] == 2.0f);
  }
  CHECK(live_tensor_bytes() == live0);            // both freed
  CHECK(peak_tensor_bytes() >= live0 + 2000000);  // the peak stays
  reset_tensor_peak();
  CHECK(peak_tensor_bytes() == live0);
  // Empty tensors, resizing and the raw interface go through the same counter.
  torch::Tensor e = torch::empty({0});
  CHECK(live_tensor_bytes() == live0);
  e.resize_({100});
  CHECK(live_tensor_bytes() == live0 + 400);
  e = torch::Tensor();
  CHECK(live_tensor_bytes() == live0);
  void* raw = c10::GetCPUAllocator()->raw_allocate(4096);
  CHECK(live_tensor_bytes() == live0 + 4096);
  c10::GetCPUAllocator()->raw_deallocate(raw);
  CHECK(live_tensor_bytes() == live0);
}
