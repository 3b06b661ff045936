// Checkpoints: one safetensors file holding the model weights under their module names ("model/..."),
// optional extra tensors, and metadata (format, step, config JSON, RNG state). Written atomically.
#pragma once
#include <functional>
#include <map>
#include <string>

#include <torch/nn/module.h>
#include <torch/types.h>

namespace isplat {

struct Checkpoint {
  std::map<std::string, torch::Tensor> tensors;  // "model/<param>", "optim/state", "rng/torch", ...
  std::map<std::string, std::string> metadata;   // "format", "step", "config", ...
  int64_t step() const;
  const std::string& config_json() const;
};

constexpr const char* kCheckpointFormat = "infinisplat-checkpoint-v1";

// Copies tensors[prefix + name] into every parameter and buffer of `module`. Missing keys, unexpected keys
// under `prefix` (unless `ignorable` says so) and shape mismatches are listed together in one Error that
// starts with `what`.
void load_named_tensors(torch::nn::Module& module, const std::map<std::string, torch::Tensor>& tensors,
                        const std::string& prefix, const std::string& what,
                        const std::function<bool(const std::string&)>& ignorable = nullptr);

// Weights and buffers of `module` under "model/<name>" (prefix configurable).
void put_module(Checkpoint& ck, const torch::nn::Module& module, const std::string& prefix = "model/");
// Copies "model/<name>" tensors into `module`; any missing, unexpected or mis-shaped tensor is listed in
// one Error naming the file.
void load_module(const Checkpoint& ck, torch::nn::Module& module, const std::string& source,
                 const std::string& prefix = "model/");

void save_checkpoint(const std::string& path, const Checkpoint& ck);  // atomic
Checkpoint load_checkpoint(const std::string& path);                  // checks the format tag

// Opaque bytes (e.g. a serialized optimizer) carried as a uint8 tensor.
torch::Tensor bytes_to_tensor(const std::string& bytes);
std::string tensor_to_bytes(const torch::Tensor& t);

// A run's checkpoint folder: periodic `step_N` files (the newest `keep_last` kept) and the names `last`
// and `best` as hard links to them (copies where the file system has none). Every write is atomic.
class CheckpointFolder {
 public:
  CheckpointFolder(std::string dir, int64_t keep_last);
  std::string path(const std::string& name) const;  // <dir>/<name>.safetensors
  // Writes step_N, points `last` at it, and removes periodic files beyond keep_last.
  void save_periodic(int64_t step, const Checkpoint& ck);
  void save(const std::string& name, const Checkpoint& ck);    // e.g. "init", or "last" on Ctrl-C
  void alias(const std::string& from, const std::string& to);  // `to` becomes the same bytes as `from`

 private:
  std::string dir_;
  int64_t keep_last_;
};

}  // namespace isplat
