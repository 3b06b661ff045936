// Checkpoints: one safetensors file holding the model weights under their module names ("model/..."),
// optional extra tensors, and metadata (format, step, config JSON, RNG state). Written atomically.
#pragma once
#include <functional>
#include <map>
#include <optional>
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

// Atomic. The metadata gets a checksum ("checksum") of every tensor's name, dtype, shape and bytes.
void save_checkpoint(const std::string& path, const Checkpoint& ck);
// Checks the format tag and, when present (checkpoints before it have none), the checksum: a flipped bit
// or an edited dtype is an Error naming the file, never loaded.
Checkpoint load_checkpoint(const std::string& path);
// The checksum save_checkpoint records: CRC-32 over names, dtypes, shapes and data, as 8 hex digits.
std::string tensors_checksum(const std::map<std::string, torch::Tensor>& tensors);

// Opaque bytes (e.g. a serialized optimizer) carried as a uint8 tensor.
torch::Tensor bytes_to_tensor(const std::string& bytes);
std::string tensor_to_bytes(const torch::Tensor& t);

// A run's checkpoint folder: periodic `step_N` files (the newest `keep_last` kept) and `last` and `best`.
// Every name is its own file (a reflink where the file system shares blocks copy-on-write, else a copy),
// so one damaged file never takes the others with it. Every write is atomic. One writer per folder: the
// trainer holds the run folder's lock.
class CheckpointFolder {
 public:
  CheckpointFolder(std::string dir, int64_t keep_last);
  std::string path(const std::string& name) const;  // <dir>/<name>.safetensors
  // Writes step_N, copies it to `last`, and removes periodic files beyond keep_last.
  void save_periodic(int64_t step, const Checkpoint& ck);
  void save(const std::string& name, const Checkpoint& ck);    // e.g. "init", or "last" on Ctrl-C
  void alias(const std::string& from, const std::string& to);  // `to` becomes a copy of `from`, atomically
  // Removes temporaries of writes that were killed (only safe while holding the run folder's lock).
  // Returns how many were removed.
  int64_t remove_stale_temporaries() const;

  // For --resume auto: `last` if it loads, else the newest of `best` and `step_N` that loads and holds an
  // optimizer state. Each file passed over is logged with its reason. None: nothing to resume.
  struct Found {
    std::string path;
    Checkpoint checkpoint;
  };
  std::optional<Found> newest_intact() const;

 private:
  std::string dir_;
  int64_t keep_last_;
};

}  // namespace isplat
