// Process-wide runtime set-up: thread count, seeds, and a report of LibTorch, threads and BLAS.
#pragma once
#include <cstdint>
#include <string>

namespace isplat {

class ConfigVisitor;

// More threads than any machine here has cores only thrashes (100000 hung at start-up).
constexpr int64_t kMaxThreads = 1024;

// Images larger than this are refused from their header, before decoding (a 20000x20000 JPEG header
// otherwise costs gigabytes). 2^27 pixels is 11585x11585, beyond any camera the readers serve.
constexpr int64_t kDefaultMaxImagePixels = int64_t{1} << 27;

struct RuntimeOptions {
  int64_t threads = 0;  // 0 = all cores
  int64_t seed = 0;
  int64_t max_image_pixels = kDefaultMaxImagePixels;
  std::string log_level = "info";
  std::string precision = "fp32";  // fp32 | bf16 | auto (core/precision.h)
  void visit(ConfigVisitor& v);
};

// Sets LibTorch's intra-op thread count (Debian's LibTorch starts with half the cores, i.e. 1 here).
// requested <= 0 means all hardware threads. Returns the count in effect.
int configure_threads(int64_t requested);

// The image size limit in effect (process-wide; apply_runtime sets it from runtime.max_image_pixels).
int64_t max_image_pixels();
void set_max_image_pixels(int64_t pixels);

// Applies threads, seeds (torch + std RNGs used by the project), the image size limit and the log level.
void apply_runtime(const RuntimeOptions& options);

// Which BLAS library libtorch resolved at load time, e.g. ".../openblas-pthread/libblas.so.3 (OpenBLAS 0.3.21 ...)".
std::string loaded_blas();

// Keeps memory the process frees for its own reuse instead of returning it to the system (glibc: no
// mmap-backed blocks, no heap trimming). Fresh pages cost a page fault each, about 8 µs on the virtual
// machines measured here: a 150 MB tensor took 300 ms to fill the first time and 5 ms once its pages were
// reused. Training steps, predictions and renders allocate such tensors again and again. The price: the
// resident size stays at its peak. Honours an explicit MALLOC_MMAP_MAX_ in the environment.
void keep_freed_memory();

// Peak resident memory of this process in MiB (Linux VmHWM; NaN where unavailable). reset_peak_memory()
// restarts the peak from the current resident size (writes 5 to /proc/self/clear_refs; false if refused),
// so a peak read afterwards belongs to the work done in between.
bool reset_peak_memory();
double peak_memory_mb();

// Measures float32 matmul throughput in GFLOP/s on an n x n product (median of a few runs).
double matmul_gflops(int n = 512);

// Multi-line report: project and LibTorch versions, threads, OpenMP, BLAS and measured GFLOP/s.
std::string runtime_report(bool measure = true);

}  // namespace isplat
