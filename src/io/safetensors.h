// safetensors read/write: 8-byte header length, JSON header, raw little-endian tensor data.
#pragma once
#include <map>
#include <string>

#include <torch/types.h>

namespace isplat {

struct SafeTensors {
  std::map<std::string, torch::Tensor> tensors;
  std::map<std::string, std::string> metadata;  // the optional "__metadata__" entry
  std::string source;

  bool has(const std::string& name) const { return tensors.count(name) > 0; }
  const torch::Tensor& at(const std::string& name) const;  // throws Error naming file and tensor
};

// Supports F64, F32, F16, BF16, I64, I32, I16, I8, U8, BOOL. Missing, truncated or corrupt files
// (bad header length, invalid JSON, offsets out of range or inconsistent with shape) throw Error.
SafeTensors read_safetensors(const std::string& path);

// Tensors are written contiguous, in name order, with the header padded to 8 bytes. Atomic.
void write_safetensors(const std::string& path, const std::map<std::string, torch::Tensor>& tensors,
                       const std::map<std::string, std::string>& metadata = {});

}  // namespace isplat
