// Precision choice and the autocast regions that apply it.
#include "core/precision.h"

#include <ATen/autocast_mode.h>
#include <cpuid.h>

#include <atomic>

#include "core/error.h"
#include "core/log.h"

namespace isplat {

bool cpu_has_bf16() {
  unsigned a = 0, b = 0, c = 0, d = 0;
  if (!__get_cpuid_count(7, 0, &a, &b, &c, &d)) return false;
  const unsigned max_subleaf = a;
  const bool amx_bf16 = (d >> 22) & 1u;
  bool avx512_bf16 = false;
  if (max_subleaf >= 1 && __get_cpuid_count(7, 1, &a, &b, &c, &d)) avx512_bf16 = (a >> 5) & 1u;
  return avx512_bf16 || amx_bf16;
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
  if (name == "bf16" && !cpu_has_bf16())
    log_warn(key, " = bf16 on a CPU without AVX512-BF16 or AMX: emulated, slower than fp32");
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
