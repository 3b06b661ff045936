// Runtime set-up and the startup report (versions, threads, BLAS).
#include "core/runtime.h"

#include <dlfcn.h>
#include <malloc.h>

#include <ATen/Parallel.h>
#include <torch/torch.h>
#include <torch/version.h>

#include <atomic>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <limits>
#include <set>
#include <thread>

#include "core/build_info.h"
#include "core/config.h"
#include "core/error.h"
#include "core/log.h"
#include "core/precision.h"

namespace isplat {

void RuntimeOptions::visit(ConfigVisitor& v) {
  v.field("threads", threads, "intra-op threads for LibTorch and our kernels; 0 = all cores",
          Range::between(0, kMaxThreads));
  v.field("seed", seed, "seed for every random choice (data, init, sampling)", Range::at_least(0));
  v.field("max_image_pixels", max_image_pixels,
          "largest image (width x height) any reader decodes; larger ones are refused from their header",
          Range::at_least(1));
  v.field("log_level", log_level, "verbosity of stderr logging", {"debug", "info", "warn", "error", "quiet"});
  v.field("precision", precision,
          "the encoder's and decoder's matmuls, attention and convolutions: fp32, bf16 (fp32 accumulation; fast "
          "where the CPU has AVX512-BF16 or AMX, emulated and slow elsewhere) or auto (bf16 where the CPU has it)",
          {"fp32", "bf16", "auto"});
}

namespace {
std::atomic<int64_t> g_max_image_pixels{kDefaultMaxImagePixels};
}

int64_t max_image_pixels() {
  return g_max_image_pixels.load();
}

void set_max_image_pixels(int64_t pixels) {
  ISPLAT_CHECK(pixels > 0, "max_image_pixels must be positive, got ", pixels);
  g_max_image_pixels = pixels;
}

int configure_threads(int64_t requested) {
  ISPLAT_CHECK(requested >= 0 && requested <= kMaxThreads, "threads: ", requested, " is outside [0, ", kMaxThreads,
               "] (runtime.threads / --threads; 0 = all cores)");
  int n = requested > 0 ? static_cast<int>(requested) : static_cast<int>(std::thread::hardware_concurrency());
  if (n <= 0) n = 1;
  at::set_num_threads(n);
  return at::get_num_threads();
}

void apply_runtime(const RuntimeOptions& options) {
  static const std::map<std::string, LogLevel> levels = {{"debug", LogLevel::Debug},
                                                         {"info", LogLevel::Info},
                                                         {"warn", LogLevel::Warn},
                                                         {"error", LogLevel::Error},
                                                         {"quiet", LogLevel::Quiet}};
  set_log_level(levels.at(options.log_level));
  configure_threads(options.threads);
  set_max_image_pixels(options.max_image_pixels);
  use_precision(options.precision, "runtime.precision");
  torch::manual_seed(static_cast<uint64_t>(options.seed));
}

void keep_freed_memory() {
  if (std::getenv("MALLOC_MMAP_MAX_") != nullptr) return;  // the user chose
  mallopt(M_MMAP_MAX, 0);
  mallopt(M_TRIM_THRESHOLD, std::numeric_limits<int>::max());
}

bool reset_peak_memory() {
  std::ofstream f("/proc/self/clear_refs");
  f << "5";
  f.flush();
  return static_cast<bool>(f);
}

double peak_memory_mb() {
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;  // "VmHWM:  1234 kB"
  return std::numeric_limits<double>::quiet_NaN();
}

std::string loaded_blas() {
  // Force BLAS to be resolved, then read which shared object provides it.
  (void)torch::mm(torch::ones({2, 2}), torch::ones({2, 2}));
  std::set<std::string> libs;
  std::ifstream maps("/proc/self/maps");
  std::string line;
  while (std::getline(maps, line)) {
    auto slash = line.find('/');
    if (slash == std::string::npos) continue;
    std::string path = line.substr(slash);
    std::string base = path.substr(path.rfind('/') + 1);
    if (base.find("blas") != std::string::npos || base.find("mkl_") != std::string::npos) libs.insert(path);
  }
  std::string out;
  for (const auto& l : libs) out += (out.empty() ? "" : ", ") + l;
  if (out.empty()) out = "none found in /proc/self/maps";
  using config_fn = char* (*)();
  if (auto fn = reinterpret_cast<config_fn>(dlsym(RTLD_DEFAULT, "openblas_get_config"))) out += cat(" (", fn(), ")");
  return out;
}

double matmul_gflops(int n) {
  torch::NoGradGuard no_grad;
  auto a = torch::rand({n, n}), b = torch::rand({n, n});
  auto c = torch::mm(a, b);  // warm-up
  std::vector<double> seconds;
  for (int r = 0; r < 5; ++r) {
    auto t0 = std::chrono::steady_clock::now();
    c = torch::mm(a, b);
    seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  std::sort(seconds.begin(), seconds.end());
  return 2.0 * n * n * static_cast<double>(n) / seconds[seconds.size() / 2] / 1e9;
}

std::string runtime_report(bool measure) {
  std::ostringstream os;
  os << "InfiniSplat-C++ " << ISPLAT_VERSION << " (commit " << build_commit() << ")\n";
  os << "LibTorch        " << TORCH_VERSION << " (CPU)\n";
  os << "threads         " << at::get_num_threads() << " intra-op of " << std::thread::hardware_concurrency()
     << " hardware threads\n";
  os << "OpenMP          " << (at::get_parallel_info().find("OpenMP") != std::string::npos ? "yes" : "no") << "\n";
  os << "BLAS            " << loaded_blas() << "\n";
  os << "precision       " << precision_name(compute_precision()) << " (CPU bf16: " << (cpu_has_bf16() ? "yes" : "no")
     << ")\n";
  auto env_or_unset = [](const char* key) {
    const char* value = std::getenv(key);
    return std::string(key) + "=" + (value ? value : "(unset)");
  };
  os << "OpenMP wait     " << env_or_unset("OMP_WAIT_POLICY") << " " << env_or_unset("GOMP_SPINCOUNT")
     << " (the executables set GOMP_SPINCOUNT=3000 when both are unset, core/startup.cpp)\n";
  if (measure) {
    const double g = matmul_gflops(512);
    os << "matmul 512^2    " << std::fixed << std::setprecision(1) << g << " GFLOP/s";
    if (g < 8.0) os << "  [slow: reference BLAS? run scripts/setup.sh to select OpenBLAS]";
    os << "\n";
  }
  return os.str();
}

}  // namespace isplat
