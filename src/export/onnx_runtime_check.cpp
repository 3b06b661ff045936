// Bridge to onnxruntime-node: raw float32 files in and out, one node process.
#include "export/onnx_runtime_check.h"

#include <unistd.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include <torch/torch.h>

#include "core/error.h"
#include "core/paths.h"
#include "io/atomic_file.h"

namespace isplat {
namespace fs = std::filesystem;

namespace {
std::string dims(const torch::Tensor& t) {
  std::string s;
  for (int64_t d : t.sizes()) s += (s.empty() ? "" : "x") + std::to_string(d);
  return s;
}
void write_raw(const std::string& path, const torch::Tensor& t) {
  auto f = t.to(torch::kFloat32).contiguous();
  std::ofstream(path, std::ios::binary).write(static_cast<const char*>(f.data_ptr()), f.numel() * 4);
}
}  // namespace

OrtRunner ort_runner_in(const std::string& root) {
  const fs::path r(root);
  return {(r / "scripts" / "ort_run.js").string(),
          (r / "third_party" / "onnxruntime-node" / "node_modules" / "onnxruntime-node").string()};
}

OrtRunner find_ort_runner() {
  // The checkout holding the executable (or the working directory) has scripts/ and third_party/.
  OrtRunner runner{resolve_shipped_path("scripts/ort_run.js"),
                   resolve_shipped_path("third_party/onnxruntime-node/node_modules/onnxruntime-node")};
  if (const char* script = std::getenv("ISPLAT_ORT_SCRIPT")) runner.script = script;
  if (const char* package = std::getenv("ISPLAT_ORT_NODE")) runner.package = package;
  return runner;
}

std::optional<torch::Tensor> run_onnxruntime(const std::string& onnx_path, const torch::Tensor& image,
                                             const torch::Tensor& uv, const OrtRunner& runner, std::string& why) {
  if (std::system("command -v node >/dev/null 2>&1") != 0) {
    why = "node is not installed";
    return std::nullopt;
  }
  const fs::path script(runner.script), package(runner.package);
  if (runner.script.empty() || !fs::exists(script)) {
    why = "the runner script ort_run.js was not found" +
          (runner.script.empty() ? std::string() : " at " + runner.script) + " (set ISPLAT_ORT_SCRIPT)";
    return std::nullopt;
  }
  if (!fs::exists(package / "package.json")) {
    why = "onnxruntime-node is not installed at " + package.string() + " (scripts/setup.sh installs it)";
    return std::nullopt;
  }
  const fs::path dir = fs::temp_directory_path() / ("isplat_ort_" + std::to_string(getpid()));
  fs::create_directories(dir);
  const std::string img = (dir / "image.bin").string(), pts = (dir / "uv.bin").string(),
                    out = (dir / "out.bin").string();
  write_raw(img, image);
  write_raw(pts, uv);
  const std::string cmd = cat("node '", script.string(), "' '", onnx_path, "' '", out, "' image=", dims(image), "='",
                              img, "' uv=", dims(uv), "='", pts, "' 2>&1");
  std::string log;
  FILE* p = popen(cmd.c_str(), "r");
  ISPLAT_CHECK(p, "cannot start node");
  std::array<char, 512> buf;
  while (fgets(buf.data(), buf.size(), p)) log += buf.data();
  const int rc = pclose(p);
  if (rc != 0) {
    fs::remove_all(dir);
    fail(onnx_path, ": ONNX Runtime failed: ", log);
  }
  const std::string bytes = read_file_bytes(out);
  fs::remove_all(dir);
  const int64_t n = uv.size(0);
  ISPLAT_CHECK(bytes.size() == static_cast<size_t>(n * 14 * 4), onnx_path, ": ONNX Runtime returned ", bytes.size(),
               " bytes, expected ", n * 14 * 4);
  auto t = torch::empty({n, 14});
  std::memcpy(t.data_ptr(), bytes.data(), bytes.size());
  return t;
}

}  // namespace isplat
