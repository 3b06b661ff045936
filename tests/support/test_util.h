// Shared test helpers: a fresh temporary folder per test and the shared-weights location.
#pragma once
#include <cstdint>
#include <functional>
#include <string>

#include <torch/types.h>

#include "core/log.h"

namespace isplat::test {

// Warnings and errors only while in scope (generation and training are chatty); restores the level.
struct QuietLogs {
  LogLevel before = log_level();
  QuietLogs() { set_log_level(LogLevel::Warn); }
  ~QuietLogs() { set_log_level(before); }
  QuietLogs(const QuietLogs&) = delete;
  QuietLogs& operator=(const QuietLogs&) = delete;
};

// Sets (or, given nullptr, unsets) an environment variable for the scope, restoring what it found after.
struct ScopedEnv {
  std::string name, before;
  bool had;
  ScopedEnv(const std::string& n, const char* value);
  ~ScopedEnv();
  ScopedEnv(const ScopedEnv&) = delete;
  ScopedEnv& operator=(const ScopedEnv&) = delete;
};

// A new empty folder under $ISPLAT_TEST_TMP (or /tmp), unique per call.
std::string temp_dir(const std::string& tag);
// The folder the weights lookup finds (core/weights.h: $INFINISPLAT_WEIGHTS, the checkout's weights/, the user
// cache) holding the SqueezeNet features and the LPIPS-squeeze heads, or "" when there is none.
std::string project_weights_dir();
// The SqueezeNet-1.1 ImageNet features there (the perceptual loss's, the encoder's and the prior's backbone).
std::string squeezenet_weights();
// The exit code ctest reads as "skipped" (SKIP_RETURN_CODE in CMakeLists.txt); catch_main never returns it.
constexpr int kSkipReturnCode = 77;
// True when the weights are found. Otherwise, under ctest ($ISPLAT_TEST_TMP set), prints why and ends the process
// with kSkipReturnCode, so ctest reports the test as skipped, never as passed; run by hand, warns and returns false.
bool weights_or_skip();
// The ATen CPU capability this process runs its vectorized kernels at, as ATen chooses it (LibTorch does not export
// it): ATEN_CPU_CAPABILITY when set, else the widest of avx512 (F, BW, DQ, VL), avx2 (with FMA), default. Golden
// values that pass through LibTorch's vectorized kernels are bit-exact only under the capability they were taken with.
std::string aten_capability();
// FNV-1a over a tensor's bytes (contiguous); 0 for an undefined tensor.
uint64_t fnv1a(const torch::Tensor& t);
// Writes raw bytes to a file (for crafting corrupt inputs).
void write_bytes(const std::string& path, const std::string& bytes);
std::string read_bytes(const std::string& path);
// The message of the isplat::Error that `f` throws, or "<no error>".
std::string error_of(const std::function<void()>& f);

}  // namespace isplat::test

// First statement of a test that needs the pretrained weights.
#define ISPLAT_REQUIRE_WEIGHTS()                    \
  do {                                              \
    if (!::isplat::test::weights_or_skip()) return; \
  } while (0)
