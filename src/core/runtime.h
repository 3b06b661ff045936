// Process-wide runtime set-up: thread count, seeds, and a report of LibTorch, threads and BLAS.
#pragma once
#include <cstdint>
#include <string>

namespace isplat {

class ConfigVisitor;

struct RuntimeOptions {
  int64_t threads = 0;  // 0 = all cores
  int64_t seed = 0;
  std::string log_level = "info";
  void visit(ConfigVisitor& v);
};

// Sets LibTorch's intra-op thread count (Debian's LibTorch starts with half the cores, i.e. 1 here).
// requested <= 0 means all hardware threads. Returns the count in effect.
int configure_threads(int64_t requested);

// Applies threads, seeds (torch + std RNGs used by the project) and the log level.
void apply_runtime(const RuntimeOptions& options);

// Which BLAS library libtorch resolved at load time, e.g. ".../openblas-pthread/libblas.so.3 (OpenBLAS 0.3.21 ...)".
std::string loaded_blas();

// Measures float32 matmul throughput in GFLOP/s on an n x n product (median of a few runs).
double matmul_gflops(int n = 512);

// Multi-line report: project and LibTorch versions, threads, OpenMP, BLAS and measured GFLOP/s.
std::string runtime_report(bool measure = true);

}  // namespace isplat
