// Data-parallel training on LibTorch's c10d engine: rendezvous through a TCPStore on rank 0 (or a
// FileStore in a shared folder), a Gloo process group, the initial weights broadcast from rank 0, and
// gradients averaged by all-reduce in a few flat buckets after every backward pass.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <torch/types.h>

namespace isplat {

class ConfigVisitor;

struct DistOptions {
  int64_t rank = 0, world_size = 1;       // also from RANK / WORLD_SIZE
  std::string master_addr = "127.0.0.1";  // MASTER_ADDR: rank 0's host (its TCPStore)
  int64_t master_port = 29500;            // MASTER_PORT
  std::string file_store;                 // rendezvous through this file in a shared folder instead of TCP
  int64_t timeout_s = 120;                // rendezvous and collective timeout: a dead rank fails the others
  double bucket_mb = 16;                  // gradient all-reduce bucket size
  void visit(ConfigVisitor& v);
};

// Applies the PyTorch launcher conventions (RANK, WORLD_SIZE, MASTER_ADDR, MASTER_PORT) over the config.
void apply_dist_environment(DistOptions& options);

class DataParallel {
 public:
  // Joins the group; fails within the timeout, naming the address and the rank, when the store cannot be
  // reached or the world size does not match.
  explicit DataParallel(const DistOptions& options);
  ~DataParallel();
  int64_t rank() const { return options_.rank; }
  int64_t world_size() const { return options_.world_size; }

  void broadcast(std::vector<torch::Tensor> tensors);                    // from rank 0, in place
  void average_gradients(const std::vector<torch::Tensor>& parameters);  // flat buckets, in place
  // Sums small per-step values (flags, losses) over ranks.
  std::vector<double> sum(const std::vector<double>& values);
  double last_allreduce_ms() const { return last_ms_; }
  int64_t bytes_per_step() const { return bytes_; }  // gradient bytes each rank contributes per step

 private:
  struct State;  // the store and the Gloo process group (c10d types stay out of this header)
  DistOptions options_;
  std::unique_ptr<State> state_;
  double last_ms_ = 0;
  int64_t bytes_ = 0;
};

}  // namespace isplat
