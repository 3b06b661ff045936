// Ordered, bounded prefetch over worker threads; workers run torch ops single-threaded.
#include "data/loader.h"

#include <omp.h>

#include "core/error.h"

namespace isplat {

BatchLoader::BatchLoader(const TupleSampler& sampler, int64_t batch_size, int64_t workers, int64_t prefetch,
                         int64_t first_batch, int64_t rank, int64_t world)
    : sampler_(sampler),
      batch_size_(batch_size),
      prefetch_(std::max<int64_t>(1, prefetch)),
      rank_(rank),
      world_(world),
      consumer_(first_batch),
      dispatched_(first_batch) {
  ISPLAT_CHECK(batch_size > 0, "batch loader: batch size must be positive");
  for (int64_t i = 0; i < workers; ++i) threads_.emplace_back([this] { worker_loop(); });
}

BatchLoader::~BatchLoader() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  cv_.notify_all();
  for (auto& t : threads_) t.join();
}

Batch BatchLoader::build(int64_t k) const {
  std::vector<TupleSample> samples;
  for (int64_t i = 0; i < batch_size_; ++i) samples.push_back(sampler_.sample((k * world_ + rank_) * batch_size_ + i));
  return collate(samples);
}

void BatchLoader::worker_loop() {
  omp_set_num_threads(1);  // loaders must not compete with the training step for the OpenMP pool
  while (true) {
    int64_t k;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      cv_.wait(lock, [this] { return stop_ || dispatched_ < consumer_ + prefetch_; });
      if (stop_) return;
      k = dispatched_++;
    }
    Batch b;
    std::string error;
    try {
      b = build(k);
    } catch (const std::exception& e) {
      error = e.what();
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (error.empty())
        ready_.emplace(k, std::move(b));
      else
        errors_.emplace(k, error);
    }
    cv_.notify_all();
  }
}

Batch BatchLoader::next() {
  if (threads_.empty()) return build(consumer_++);
  std::unique_lock<std::mutex> lock(mutex_);
  cv_.wait(lock, [this] { return ready_.count(consumer_) || errors_.count(consumer_); });
  auto err = errors_.find(consumer_);
  if (err != errors_.end()) fail(err->second);
  Batch b = std::move(ready_.at(consumer_));
  ready_.erase(consumer_);
  ++consumer_;
  lock.unlock();
  cv_.notify_all();
  return b;
}

}  // namespace isplat
