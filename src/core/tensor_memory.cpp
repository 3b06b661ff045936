// The counting CPU allocator behind core/tensor_memory.h.
#include "core/tensor_memory.h"

#include <c10/core/Allocator.h>
#include <c10/core/CPUAllocator.h>
#include <c10/core/alignment.h>
#include <c10/core/impl/alloc_cpu.h>

#include <atomic>
#include <mutex>

namespace isplat {
namespace {

std::atomic<int64_t> g_tensor_live{0}, g_tensor_peak{0};
std::atomic<bool> g_tensor_counting{false};

// Each block carries its size in a header of one alignment unit, so the data stays as aligned as c10's own blocks
// and the pointer is its own context (raw_allocate works).
constexpr size_t kCountedHeader = c10::gAlignment;
static_assert(kCountedHeader >= sizeof(int64_t) && kCountedHeader % alignof(int64_t) == 0);

void raise_tensor_peak(int64_t live) {
  int64_t peak = g_tensor_peak.load(std::memory_order_relaxed);
  while (live > peak && !g_tensor_peak.compare_exchange_weak(peak, live, std::memory_order_relaxed)) {
  }
}

void release_counted(void* data) {
  if (data == nullptr) return;
  char* block = static_cast<char*>(data) - kCountedHeader;
  g_tensor_live.fetch_sub(*reinterpret_cast<int64_t*>(block), std::memory_order_relaxed);
  c10::free_cpu(block);
}

struct CountingCpuAllocator final : c10::Allocator {
  c10::DataPtr allocate(size_t n) const override {
    if (n == 0) return {nullptr, nullptr, &release_counted, c10::Device(c10::DeviceType::CPU)};
    char* block = static_cast<char*>(c10::alloc_cpu(n + kCountedHeader));
    *reinterpret_cast<int64_t*>(block) = static_cast<int64_t>(n);
    raise_tensor_peak(g_tensor_live.fetch_add(static_cast<int64_t>(n), std::memory_order_relaxed) +
                      static_cast<int64_t>(n));
    void* data = block + kCountedHeader;
    return {data, data, &release_counted, c10::Device(c10::DeviceType::CPU)};
  }
  c10::DeleterFnPtr raw_deleter() const override { return &release_counted; }
};

}  // namespace

void count_tensor_memory() {
  static std::once_flag once;
  std::call_once(once, [] {
    // Never destroyed: c10 keeps the pointer, and frees during exit still reach it.
    c10::SetCPUAllocator(new CountingCpuAllocator, /*priority=*/1);
    g_tensor_counting = true;
  });
}

bool tensor_memory_counted() {
  return g_tensor_counting;
}

int64_t live_tensor_bytes() {
  return g_tensor_live.load(std::memory_order_relaxed);
}

void reset_tensor_peak() {
  g_tensor_peak.store(g_tensor_live.load(std::memory_order_relaxed), std::memory_order_relaxed);
}

int64_t peak_tensor_bytes() {
  return g_tensor_peak.load(std::memory_order_relaxed);
}

}  // namespace isplat
