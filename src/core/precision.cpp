// Precision choice and the autocast regions that apply it.
#include "core/precision.h"

#include <ATen/autocast_mode.h>
#include <cpuid.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cstdlib>

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
}  // namespace

bool onednn_isa_excludes_bf16(std::string isa) {
  std::transform(isa.begin(), isa.end(), isa.begin(), [](unsigned char c) { return char(std::toupper(c)); });
  // oneDNN's names of the instruction sets below its bf16 kernels; any other value (ALL, DEFAULT, the bf16 and AMX
  // ones, names newer than oneDNN 2.6) leaves them on.
  for (const char* below : {"SSE41", "AVX", "AVX2", "AVX2_VNNI", "AVX2_VNNI_2", "AVX512_MIC", "AVX512_MIC_4OPS",
                            "AVX512_CORE", "AVX512_CORE_VNNI"})
    if (isa == below) return true;
  return false;
}

std::string onednn_bf16_cap() {
  for (const char* name : {"ONEDNN_MAX_CPU_ISA", "DNNL_MAX_CPU_ISA"}) {  // oneDNN reads the first one set
    const char* value = std::getenv(name);
    if (value == nullptr || *value == 0) continue;
    return onednn_isa_excludes_bf16(value) ? std::string(name) + "=" + value : std::string();
  }
  return {};
}

bool cpu_has_bf16() {
  return cpuid_has_bf16() && onednn_bf16_cap().empty();
}

Precision resolve_precision(const std::string& name, const std::string& key) {
  if (name == "fp32") return Precision::fp32;
  if (name == "bf16") return Precision::bf16;
  if (name == "auto") return cpu_has_bf16() ? Precision::bf16 : Precision::fp32;
  fail(key, " = '", name, "' is not a precision: use fp32, bf16 or auto");
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
  set_compute_precision(resolve_precision(name, key));
  if (name != "bf16") return;
  // LibTorch sends bf16 matmuls to oneDNN whenever the CPU has the instructions, and a capped oneDNN then fails.
  if (const std::string cap = onednn_bf16_cap(); cpuid_has_bf16() && !cap.empty())
    fail(key, " = bf16, but ", cap, " keeps oneDNN off its bf16 kernels: unset it, or use fp32 or auto");
  if (!cpu_has_bf16()) log_warn(key, " = bf16 on a CPU without AVX512-BF16 or AMX: emulated, slower than fp32");
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
