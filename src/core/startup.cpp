// Start-up, before any library initializes: OpenMP's idle workers sleep instead of spinning (OMP_WAIT_POLICY).
//
// Why: libgomp's workers spin for milliseconds after every parallel region by default. On a 2-core machine that
// spinning takes the core OpenBLAS's worker needs for the matmul that follows, so every GEMM after an elementwise
// op runs at about half speed (measured on a Zen 4: the ViT-S encoder 270-720 ms -> 150-180 ms, a training step
// 25-35% faster, the renderer unchanged). docs/results/2026-12-02-openmp-wait.md has the figures.
//
// How: libgomp reads OMP_WAIT_POLICY once, in its own constructor, so a setenv() in main() is too late. A
// .preinit_array function runs before every library constructor, but also before libc has set up `environ`, so
// a setenv() there is lost too. What works is to re-execute the program once with the variable added (about
// 25 ms of dynamic loading, before LibTorch's static initializers run). A value the user set is never changed,
// so OMP_WAIT_POLICY=active restores libgomp's default. This object is linked into every executable
// (CMakeLists.txt: isplat_startup), not into the library, which must not re-execute its host program.
#include <alloca.h>
#include <string.h>
#include <unistd.h>

namespace {

constexpr char kWaitKey[] = "OMP_WAIT_POLICY=";
char kWaitPassive[] = "OMP_WAIT_POLICY=passive";

void sleep_idle_openmp_workers(int /*argc*/, char** argv, char** envp) {
  if (envp == nullptr || argv == nullptr || argv[0] == nullptr) return;
  size_t n = 0;
  for (; envp[n] != nullptr; ++n)
    if (strncmp(envp[n], kWaitKey, sizeof(kWaitKey) - 1) == 0) return;  // set by the user or by the re-exec
  // No allocator yet: the new environment lives on this stack frame, which execve replaces.
  auto** env = static_cast<char**>(alloca((n + 2) * sizeof(char*)));
  memcpy(env, envp, n * sizeof(char*));
  env[n] = kWaitPassive;
  env[n + 1] = nullptr;
  execve("/proc/self/exe", argv, env);
  // Only reached when execve failed (no /proc): run on with libgomp's default, which is slower, not wrong.
}

}  // namespace

// Functions in .preinit_array run before the constructors of every shared library, libgomp's included.
__attribute__((section(".preinit_array"),
               used)) static void (*const isplat_preinit)(int, char**, char**) = &sleep_idle_openmp_workers;
