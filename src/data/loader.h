// A multi-threaded batch loader with prefetch: batch k holds tuples [k*B, (k+1)*B) of a TupleSampler,
// so its content depends only on the seed and k, whichever worker builds it.
#pragma once
#include <condition_variable>
#include <cstdint>
#include <map>
#include <mutex>
#include <thread>
#include <vector>

#include "data/tuples.h"

namespace isplat {

class BatchLoader {
 public:
  // Starts `workers` threads (0 = load synchronously in next()) that keep up to `prefetch` batches
  // ready, beginning at batch `first_batch` (for resumed runs).
  // Batch k holds tuples (k * world + rank) * batch_size + i: with `world` data-parallel ranks each draws a
  // disjoint, deterministic share of every global batch.
  BatchLoader(const TupleSampler& sampler, int64_t batch_size, int64_t workers, int64_t prefetch,
              int64_t first_batch = 0, int64_t rank = 0, int64_t world = 1);
  ~BatchLoader();
  BatchLoader(const BatchLoader&) = delete;
  BatchLoader& operator=(const BatchLoader&) = delete;

  Batch next();  // blocks until the next batch in order is ready; rethrows a worker's error
  int64_t next_index() const { return consumer_; }

 private:
  Batch build(int64_t k) const;
  void worker_loop();

  const TupleSampler& sampler_;
  int64_t batch_size_, prefetch_, rank_ = 0, world_ = 1;
  int64_t consumer_;    // next batch handed out
  int64_t dispatched_;  // next batch a worker will build
  std::map<int64_t, Batch> ready_;
  std::map<int64_t, std::string> errors_;
  std::mutex mutex_;
  std::condition_variable cv_;
  bool stop_ = false;
  std::vector<std::thread> threads_;
};

}  // namespace isplat
