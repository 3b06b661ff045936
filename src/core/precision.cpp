// Precision choice and the autocast regions that apply it.
#include "core/precision.h"

#include <ATen/autocast_mode.h>
#include <cpuid.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cstdlib>
#include <utility>

#include "core/error.h"
#include "core/log.h"

namespace isplat {

namespace {
bool cpuid_has_bf16() {
  unsigned a = 0, b = 0, c = 0, d = 0;
  if (!__get_cpuid_count(7, 0, &a, &b, &c, &d)) return false;
  const unsigned max_subleaf = a;
  const bool amx_bf16 = (d >> 22) & 1u;
  bool avx512_bf16 = false;
  if (max_subleaf >= 1 && __get_cpuid_count(7, 1, &a, &b, &c, &d)) avx512_bf16 = (a >> 5) & 1u;
  return avx512_bf16 || amx_bf16;
}

// The cap oneDNN reads (the first of its two variable names that is set): {name, value}, or two empty strings.
std::pair<std::string, std::string> onednn_isa_cap() {
  for (const char* name : {"ONEDNN_MAX_CPU_ISA", "DNNL_MAX_CPU_ISA"})
    if (const char* value = std::getenv(name); value != nullptr && *value != 0) return {name, value};
  return {};
}
}  // namespace

bool cpu_sends_bf16_to_onednn() {
  return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw") &&
         __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512vl");
}

OnednnBf16 onednn_bf16_under_cap(std::string isa) {
  std::transform(isa.begin(), isa.end(), isa.begin(), [](unsigned char c) { return char(std::toupper(c)); });
  // oneDNN 2.6's names below AVX512_CORE (no bf16 kernel at all; seen failing at AVX2 and AVX2_VNNI), and the two
  // AVX-512 levels below the bf16 instructions (bf16 runs, emulated; seen). Any other name (ALL, DEFAULT, the bf16
  // and AMX levels, names newer than oneDNN 2.6) leaves the native kernels on.
  for (const char* below : {"SSE41", "AVX", "AVX2", "AVX2_VNNI", "AVX2_VNNI_2", "AVX512_MIC", "AVX512_MIC_4OPS"})
    if (isa == below) return OnednnBf16::none;
  for (const char* emulated : {"AVX512_CORE", "AVX512_CORE_VNNI"})
    if (isa == emulated) return OnednnBf16::emulated;
  return OnednnBf16::native;
}

std::string onednn_bf16_cap() {
  const auto [name, value] = onednn_isa_cap();
  if (name.empty() || onednn_bf16_under_cap(value) == OnednnBf16::native) return {};
  return name + "=" + value;
}

bool cpu_has_bf16() {
  return cpuid_has_bf16() && onednn_bf16_cap().empty();
}

Precision resolve_precision(const std::string& name, const std::string& key) {
  if (name == "fp32") return Precision::fp32;
  if (name == "auto") return cpu_has_bf16() ? Precision::bf16 : Precision::fp32;
  if (name != "bf16") fail(key, " = '", name, "' is not a precision: use fp32, bf16 or auto");
  // LibTorch sends bf16 matmuls to oneDNN on AVX-512 CPUs, and a oneDNN capped below AVX-512 then fails at the first.
  const auto [cap, value] = onednn_isa_cap();
  if (!cap.empty() && onednn_bf16_under_cap(value) == OnednnBf16::none && cpu_sends_bf16_to_onednn())
    fail(key, " = bf16, but ", cap, "=", value,
         " leaves oneDNN no bf16 kernel, and LibTorch sends bf16 matmuls to it on this CPU: unset it (or allow at "
         "least AVX512_CORE), or use fp32 or auto");
  return Precision::bf16;
}

const char* precision_name(Precision p) {
  return p == Precision::bf16 ? "bf16" : "fp32";
}

namespace {
std::atomic<Precision> g_precision{Precision::fp32};
}

void set_compute_precision(Precision p) {
  g_precision = p;
}

Precision compute_precision() {
  return g_precision.load();
}

void use_precision(const std::string& name, const std::string& key) {
  const Precision p = resolve_precision(name, key);  // throws before anything changes
  set_compute_precision(p);
  if (p == Precision::bf16 && !cpu_has_bf16()) {
    const std::string cap = onednn_bf16_cap();
    log_warn(key, " = bf16 ",
             cpuid_has_bf16() ? "with oneDNN capped below its bf16 instructions (" + cap + ")"
                              : std::string("on a CPU without AVX512-BF16 or AMX"),
             ": emulated, slower than fp32");
  }
}

Bf16Region::Bf16Region(bool enabled) : active_(enabled) {
  if (!active_) return;
  was_enabled_ = at::autocast::is_cpu_enabled();
  was_dtype_ = static_cast<int>(at::autocast::get_autocast_cpu_dtype());
  at::autocast::set_autocast_cpu_dtype(at::kBFloat16);
  at::autocast::set_cpu_enabled(true);
  at::autocast::increment_nesting();
}

Bf16Region::~Bf16Region() {
  if (!active_) return;
  if (at::autocast::decrement_nesting() == 0) at::autocast::clear_cache();
  at::autocast::set_cpu_enabled(was_enabled_);
  at::autocast::set_autocast_cpu_dtype(static_cast<at::ScalarType>(was_dtype_));
}

Fp32Region::Fp32Region() : was_enabled_(at::autocast::is_cpu_enabled()) {
  at::autocast::set_cpu_enabled(false);
}

Fp32Region::~Fp32Region() {
  at::autocast::set_cpu_enabled(was_enabled_);
}

}  // namespace isplat
