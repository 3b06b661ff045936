// Failures that cannot name their cause (a LibTorch check, out of memory, another library's exception) end with
// what the program was doing when they happened (issue 74, item 5): core/error.h's ErrorContext and run_main.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <new>

#include <c10/util/Exception.h>
#include <torch/torch.h>

#include "core/app.h"
#include "core/error.h"
#include "support/test_util.h"

using namespace isplat;

namespace {

// run_main's exit code and the line it writes to stderr.
std::pair<int, std::string> ec_run_main(const std::function<int()>& body) {
  // run_main first tunes malloc for the executables (keep_freed_memory); the user's choice in the environment keeps
  // this test process as it was.
  const bool had = std::getenv("MALLOC_MMAP_MAX_") != nullptr;
  if (!had) ::setenv("MALLOC_MMAP_MAX_", "65536", 0);
  std::fflush(stderr);
  const std::string path = test::temp_dir("ec_stderr") + "/err.txt";
  const int saved = ::dup(2);
  std::FILE* file = std::fopen(path.c_str(), "w");
  ::dup2(::fileno(file), 2);
  const int rc = run_main("tool", body);
  std::fflush(stderr);
  ::dup2(saved, 2);
  ::close(saved);
  std::fclose(file);
  if (!had) ::unsetenv("MALLOC_MMAP_MAX_");
  return {rc, test::read_bytes(path)};
}

}  // namespace

TEST_CASE("error context: LibTorch errors and out of memory say what was being done", "[namederrors][context]") {
  const auto [rc, text] = ec_run_main([] {
    ErrorContext outer("predicting photo.jpg");
    ErrorContext inner("reading the PLY scene.ply");
    // A real LibTorch check: a reshape that cannot be.
    (void)torch::zeros({6}).reshape({4, 4});
    return 0;
  });
  CHECK(rc == 1);
  CHECK_THAT(text, Catch::Contains("is invalid for input of size 6") &&
                       Catch::Contains("(while reading the PLY scene.ply; predicting photo.jpg)"));

  const auto [rc2, text2] = ec_run_main([]() -> int {
    ErrorContext c("decoding the image big.png");
    throw std::bad_alloc();
  });
  CHECK(rc2 == 1);
  CHECK_THAT(text2, Catch::Contains("tool: out of memory (while decoding the image big.png)"));
}

TEST_CASE("error context: a handled failure leaves no story for the next one", "[namederrors][context]") {
  const auto [rc, text] = ec_run_main([]() -> int {
    try {
      ErrorContext c("reading old.ply");
      throw std::runtime_error("handled");
    } catch (const std::runtime_error&) {
    }
    ErrorContext next("rendering new.ply");
    fail("render: camera focal lengths must be positive");
  });
  CHECK(rc == 1);
  CHECK_THAT(text, Catch::Contains("render: camera focal lengths must be positive (while rendering new.ply)"));
  CHECK(text.find("old.ply") == std::string::npos);
}

TEST_CASE("error context: the project's errors that name the file are not repeated", "[namederrors][context]") {
  for (const char* named : {"/data/a/scene.ply: vertex 1 is bad", "scene.ply: vertex 1 is bad"}) {
    const auto [rc, text] = ec_run_main([&]() -> int {
      ErrorContext c("reading the PLY /data/a/scene.ply");
      fail(named);
    });
    CHECK(rc == 1);
    CHECK_THAT(text, Catch::Contains(named));
    CHECK(text.find("while") == std::string::npos);
  }
  // Without a context the message is the error's own.
  const auto [rc2, text2] = ec_run_main([]() -> int { fail("x.json: broken"); });
  CHECK(rc2 == 1);
  CHECK(text2.find("while") == std::string::npos);
}
