// Shared test helpers.
#include "support/test_util.h"

#include "core/error.h"

#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <fstream>
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
  // The weights that ship in the repository (weights/README.md); their sha256 is its own test.
  return (fs::path(ISPLAT_SOURCE_DIR) / "weights").string();
}

std::string squeezenet_weights() {
  return project_weights_dir() + "/squeezenet1_1_features.safetensors";
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
