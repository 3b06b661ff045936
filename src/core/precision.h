// Compute precision of the encoder's and decoder's matmuls and convolutions: fp32, or bf16 with fp32 accumulation.
#pragma once
#include <string>

namespace isplat {

enum class Precision { fp32, bf16 };

// True when the CPU has AVX512-BF16 or AMX-BF16 (oneDNN's bf16 matmul and convolution kernels) and no oneDNN ISA cap
// (ONEDNN_MAX_CPU_ISA, DNNL_MAX_CPU_ISA) keeps oneDNN below them.
bool cpu_has_bf16();

// True on CPUs with AVX-512 F, BW, VL and DQ, where LibTorch 1.13 sends bf16 matmuls and convolutions to oneDNN.
bool cpu_sends_bf16_to_onednn();

// What a oneDNN instruction-set cap (its name, any case) leaves of bf16: the native kernels (AVX512_CORE_BF16, AMX,
// ALL, unknown names), emulated ones (AVX512_CORE, AVX512_CORE_VNNI), or none (AVX2 and below).
enum class OnednnBf16 { native, emulated, none };
OnednnBf16 onednn_bf16_under_cap(std::string isa);
// "ONEDNN_MAX_CPU_ISA=AVX2" (the variable and its value) when the environment caps oneDNN below its native bf16
// kernels, else "".
std::string onednn_bf16_cap();

// "fp32" | "bf16" | "auto" (bf16 where cpu_has_bf16(), else fp32); anything else is an error naming `key`, and so is
// bf16 on an AVX-512 CPU whose oneDNN is capped below AVX-512 (LibTorch's bf16 matmuls would fail there).
Precision resolve_precision(const std::string& name, const std::string& key = "runtime.precision");
const char* precision_name(Precision p);

// Process-wide: what the model's encoder and decoder run in (apply_runtime sets it from runtime.precision).
void set_compute_precision(Precision p);
Precision compute_precision();

// Resolves `name` (an error naming `key`, as resolve_precision says, changes nothing), makes it the process-wide
// precision, and warns when bf16 can only be emulated: what runtime.precision and every --precision flag do.
void use_precision(const std::string& name, const std::string& key);

// Sets the process-wide precision while alive, then restores the one it found (one method of an evaluation).
class PrecisionScope {
 public:
  explicit PrecisionScope(Precision p) : was_(compute_precision()) { set_compute_precision(p); }
  ~PrecisionScope() { set_compute_precision(was_); }
  PrecisionScope(const PrecisionScope&) = delete;
  PrecisionScope& operator=(const PrecisionScope&) = delete;

 private:
  Precision was_;
};

// While alive and `enabled`, LibTorch's CPU autocast runs matmuls, linears and convolutions in bf16 (their outputs
// are bf16; everything else keeps its input type). Weights stay fp32: their bf16 copies are cached per region and
// dropped when the outermost region ends, so an optimizer step between regions is always seen.
class Bf16Region {
 public:
  explicit Bf16Region(bool enabled);
  ~Bf16Region();
  Bf16Region(const Bf16Region&) = delete;
  Bf16Region& operator=(const Bf16Region&) = delete;

 private:
  bool active_ = false, was_enabled_ = false;
  int was_dtype_ = 0;
};

// While alive, autocast is off (code that must see fp32 inside a Bf16Region, e.g. our own float kernels' inputs).
class Fp32Region {
 public:
  Fp32Region();
  ~Fp32Region();
  Fp32Region(const Fp32Region&) = delete;
  Fp32Region& operator=(const Fp32Region&) = delete;

 private:
  bool was_enabled_;
};

}  // namespace isplat
