// Shared test helpers.
#include "support/test_util.h"

#include <catch2/catch.hpp>

#include "core/error.h"
#include "core/weights.h"

#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <vector>

namespace isplat::test {
namespace fs = std::filesystem;

std::string temp_dir(const std::string& tag) {
  static std::atomic<int> counter{0};
  const char* root = std::getenv("ISPLAT_TEST_TMP");
  fs::path base = root ? fs::path(root) : fs::temp_directory_path() / "isplat_tests";
  fs::path dir = base / (tag + "_" + std::to_string(getpid()) + "_" + std::to_string(counter++));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir.string();
}

std::string project_weights_dir() {
  return find_weights_folder({kSqueezeNetFeatures, kLpipsSqueezeHeads});
}

std::string squeezenet_weights() {
  const std::string dir = project_weights_dir();
  return dir.empty() ? "" : (fs::path(dir) / kSqueezeNetFeatures).string();
}

bool weights_or_skip() {
  if (!project_weights_dir().empty()) return true;
  const std::string why = "skipped: no pretrained weights (" + missing_weights_hint() + ")";
  if (std::getenv("ISPLAT_TEST_TMP")) {  // set by ctest only (CMakeLists.txt)
    std::cout << why << std::endl;
    std::_Exit(kSkipReturnCode);
  }
  WARN(why);
  SUCCEED(why);
  return false;
}

ScopedEnv::ScopedEnv(const std::string& n, const char* value) : name(n) {
  const char* old = std::getenv(n.c_str());
  had = old != nullptr;
  before = had ? old : "";
  value ? setenv(n.c_str(), value, 1) : unsetenv(n.c_str());
}
ScopedEnv::~ScopedEnv() {
  had ? setenv(name.c_str(), before.c_str(), 1) : unsetenv(name.c_str());
}

std::string aten_capability() {
  if (const char* env = std::getenv("ATEN_CPU_CAPABILITY")) return env;
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512dq") &&
      __builtin_cpu_supports("avx512vl"))
    return "avx512";
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) return "avx2";
  return "default";
}

uint64_t fnv1a(const torch::Tensor& t) {
  if (!t.defined()) return 0;
  const torch::Tensor c = t.contiguous();
  const auto* p = static_cast<const unsigned char*>(c.data_ptr());
  const size_t n = static_cast<size_t>(c.numel()) * c.element_size();
  uint64_t h = 1469598103934665603ull;
  for (size_t k = 0; k < n; ++k) h = (h ^ p[k]) * 1099511628211ull;
  return h;
}

void write_bytes(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

std::string read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "<no error>";
}

}  // namespace isplat::test
