// Compute precision of the encoder's and decoder's matmuls and convolutions: fp32, or bf16 with fp32 accumulation.
#pragma once
#include <string>

namespace isplat {

enum class Precision { fp32, bf16 };

// True when the CPU has AVX512-BF16 or AMX-BF16 (oneDNN's bf16 matmul and convolution kernels) and no oneDNN ISA cap
// (ONEDNN_MAX_CPU_ISA, DNNL_MAX_CPU_ISA) keeps oneDNN below them.
bool cpu_has_bf16();

// "ONEDNN_MAX_CPU_ISA=AVX2" (the variable and its value) when that cap keeps oneDNN off its bf16 kernels, else "".
std::string onednn_bf16_cap();
// True for oneDNN's names of the instruction sets below its bf16 kernels (SSE41 ... AVX512_CORE_VNNI, any case).
bool onednn_isa_excludes_bf16(std::string isa);

// "fp32" | "bf16" | "auto" (bf16 where cpu_has_bf16(), else fp32); anything else is an error naming `key`.
Precision resolve_precision(const std::string& name, const std::string& key = "runtime.precision");
const char* precision_name(Precision p);

// Process-wide: what the model's encoder and decoder run in (apply_runtime sets it from runtime.precision).
void set_compute_precision(Precision p);
Precision compute_precision();

// Resolves `name` (an error naming `key` if it is none), makes it the process-wide precision, and warns when bf16 is
// asked for on a CPU that can only emulate it: what runtime.precision and every --precision flag do.
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
