// Start-up, before any library initializes: OpenMP's idle workers spin briefly, then sleep (GOMP_SPINCOUNT).
//
// Why: libgomp's workers spin for about 3 ms (300,000 spins) after every parallel region by default. On a 2-core
// machine that spinning takes the core OpenBLAS's worker needs for the matmul that follows, so every GEMM after an
// elementwise op runs at about half speed. Sleeping at once (OMP_WAIT_POLICY=passive) frees the core but makes
// back-to-back small ops (the optimizer's, the renderer's) wait for a wake-up; 3,000 spins keep those and free the
// core within tens of microseconds (measured on a Zen 4, with the decoder's vectorized queries beside it: a
// prediction 0.91-1.32 s -> 0.56-0.71 s, the ViT-S encoder's share halved). lab/2026-12-02-openmp-wait.
//
// How: libgomp reads its environment once, in its own constructor, so a setenv() in main() is too late. A
// .preinit_array function runs before every library constructor, but also before libc has set up `environ`, so
// a setenv() there is lost too. What works is to re-execute the program once with the variable added (about
// 25 ms of dynamic loading, before LibTorch's static initializers run). When the user set OMP_WAIT_POLICY or
// GOMP_SPINCOUNT, nothing is changed, so GOMP_SPINCOUNT=300000 restores libgomp's default. This object is linked
// into every executable (CMakeLists.txt: isplat_startup), not into the library, which must not re-execute its host.
#include <alloca.h>
#include <string.h>
#include <unistd.h>

namespace {

constexpr char kPolicyKey[] = "OMP_WAIT_POLICY=";
constexpr char kSpinKey[] = "GOMP_SPINCOUNT=";
char kShortSpin[] = "GOMP_SPINCOUNT=3000";

bool starts_with(const char* entry, const char* key, size_t length) {
  return strncmp(entry, key, length) == 0;
}

void shorten_openmp_spin(int /*argc*/, char** argv, char** envp) {
  if (envp == nullptr || argv == nullptr || argv[0] == nullptr) return;
  size_t n = 0;
  for (; envp[n] != nullptr; ++n)
    if (starts_with(envp[n], kPolicyKey, sizeof(kPolicyKey) - 1) ||
        starts_with(envp[n], kSpinKey, sizeof(kSpinKey) - 1))
      return;  // the user's choice, or set by the re-exec
  // No allocator yet: the new environment lives on this stack frame, which execve replaces.
  auto** env = static_cast<char**>(alloca((n + 2) * sizeof(char*)));
  memcpy(env, envp, n * sizeof(char*));
  env[n] = kShortSpin;
  env[n + 1] = nullptr;
  execve("/proc/self/exe", argv, env);
  // Only reached when execve failed (no /proc): run on with libgomp's default, which is slower, not wrong.
}

}  // namespace

// Functions in .preinit_array run before the constructors of every shared library, libgomp's included.
__attribute__((section(".preinit_array"), used)) static void (*const isplat_preinit)(int, char**,
                                                                                     char**) = &shorten_openmp_spin;
