// c10d/Gloo data parallelism: store rendezvous with clear failures, bucketed gradient averaging.
#include "train/data_parallel.h"

#include <torch/torch.h>
#include <torch/csrc/distributed/c10d/FileStore.hpp>
#include <torch/csrc/distributed/c10d/PrefixStore.hpp>
#include <torch/csrc/distributed/c10d/ProcessGroupGloo.hpp>
#include <torch/csrc/distributed/c10d/TCPStore.hpp>

#include <chrono>
#include <cstdlib>

#include "core/config.h"
#include "core/error.h"
#include "core/log.h"
#include "core/parse.h"

namespace isplat {

void DistOptions::visit(ConfigVisitor& v) {
  v.field("rank", rank, "this process's rank (env RANK overrides)", Range::at_least(0));
  v.field("world_size", world_size, "number of ranks; 1 = no data parallelism (env WORLD_SIZE)",
          Range::between(1, 4096));
  v.field("master_addr", master_addr, "rank 0's address: it hosts the TCPStore (env MASTER_ADDR)");
  v.field("master_port", master_port, "rank 0's TCPStore port (env MASTER_PORT)", Range::between(1, 65535));
  v.field("file_store", file_store, "rendezvous through this file (a shared folder) instead of TCP");
  v.field("timeout_s", timeout_s, "seconds to wait for the other ranks (rendezvous and every collective)",
          Range::between(1, 86400));
  v.field("bucket_mb", bucket_mb, "gradient all-reduce bucket size in MB", Range::between(0.01, 4096));
}

void apply_dist_environment(DistOptions& o) {
  auto env_int = [](const char* name, int64_t& out) {
    if (const char* v = std::getenv(name)) {
      const auto n = parse_int(v);
      ISPLAT_CHECK(n.has_value(), "environment variable ", name, "='", v, "' is not an integer");
      out = *n;
    }
  };
  env_int("RANK", o.rank);
  env_int("WORLD_SIZE", o.world_size);
  env_int("MASTER_PORT", o.master_port);
  if (const char* v = std::getenv("MASTER_ADDR")) o.master_addr = v;
  ISPLAT_CHECK(o.world_size >= 1 && o.rank >= 0 && o.rank < o.world_size, "data parallel: rank ", o.rank,
               " is not in [0, world size ", o.world_size, ") (RANK / WORLD_SIZE or dist.rank / dist.world_size)");
  ISPLAT_CHECK(o.master_port >= 1 && o.master_port <= 65535, "data parallel: MASTER_PORT ", o.master_port,
               " is not a port");
}

struct DataParallel::State {
  c10::intrusive_ptr<c10d::Store> store;
  c10::intrusive_ptr<c10d::ProcessGroupGloo> group;
};

namespace {
std::string where(const DistOptions& o) {
  return o.file_store.empty() ? cat("store tcp://", o.master_addr, ":", o.master_port)
                              : cat("file store ", o.file_store);
}

void wait_for(const c10::intrusive_ptr<c10d::Work>& work, const DistOptions& o, const std::string& what) {
  try {
    work->wait(std::chrono::seconds(o.timeout_s));
  } catch (const std::exception& e) {
    fail("data parallel: rank ", o.rank, " of ", o.world_size, ": ", what, " failed (", where(o),
         "); another rank probably stopped or died: ", e.what());
  }
}
}  // namespace

DataParallel::DataParallel(const DistOptions& o) : options_(o), state_(std::make_unique<State>()) {
  const auto timeout = std::chrono::milliseconds(o.timeout_s * 1000);
  try {
    if (!o.file_store.empty()) {
      state_->store = c10::make_intrusive<c10d::FileStore>(o.file_store, static_cast<int>(o.world_size));
    } else {
      c10d::TCPStoreOptions so;
      so.port = static_cast<uint16_t>(o.master_port);
      so.isServer = o.rank == 0;
      so.numWorkers = static_cast<size_t>(o.world_size);
      so.waitWorkers = false;
      so.timeout = timeout;
      state_->store = c10::make_intrusive<c10d::TCPStore>(o.master_addr, so);
    }
    state_->store->setTimeout(timeout);
    // Every rank states the world size it was given; a mismatch is caught before the group forms.
    auto prefix = c10::make_intrusive<c10d::PrefixStore>("isplat", state_->store);
    const std::string size = std::to_string(o.world_size);
    prefix->set(cat("world_size/", o.rank), std::vector<uint8_t>(size.begin(), size.end()));
    const int64_t joined = prefix->add("joined", 1);
    ISPLAT_CHECK(joined <= o.world_size, "data parallel: rank ", o.rank, " is rank number ", joined, " to join ",
                 where(o), ", but the world size is ", o.world_size, " (WORLD_SIZE differs between ranks?)");
    for (int64_t r = 0; r < o.world_size; ++r) {
      const auto v = prefix->get(cat("world_size/", r));  // waits (up to the timeout) for rank r
      const std::string theirs(v.begin(), v.end());
      ISPLAT_CHECK(theirs == size, "data parallel: rank ", r, " was started with world size ", theirs, ", rank ",
                   o.rank, " with ", size, " (", where(o), ")");
    }
    auto opts = c10d::ProcessGroupGloo::Options::create(timeout);
    // Loopback for one machine; across machines the interface named by GLOO_SOCKET_IFNAME, or the address
    // this host's name resolves to (PyTorch's rules).
    const bool local = o.master_addr == "127.0.0.1" || o.master_addr == "localhost";
    if (const char* ifname = std::getenv("GLOO_SOCKET_IFNAME"))
      opts->devices.push_back(c10d::ProcessGroupGloo::createDeviceForInterface(ifname));
    else
      opts->devices.push_back(local ? c10d::ProcessGroupGloo::createDeviceForHostname("127.0.0.1")
                                    : c10d::ProcessGroupGloo::createDefaultDevice());
    opts->threads = 1;
    state_->group =
        c10::make_intrusive<c10d::ProcessGroupGloo>(c10::make_intrusive<c10d::PrefixStore>("gloo", state_->store),
                                                    static_cast<int>(o.rank), static_cast<int>(o.world_size), opts);
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    fail("data parallel: rank ", o.rank, " of ", o.world_size, " could not join the group through ", where(o),
         " within ", o.timeout_s, " s: ", e.what());
  }
  log_info("data parallel: rank ", o.rank, " of ", o.world_size, " joined through ", where(o));
}

DataParallel::~DataParallel() = default;

void DataParallel::broadcast(std::vector<torch::Tensor> tensors) {
  if (tensors.empty()) return;
  torch::NoGradGuard g;
  std::vector<torch::Tensor> flat = {torch::cat([&] {
    std::vector<torch::Tensor> parts;
    for (const auto& t : tensors) parts.push_back(t.detach().reshape(-1).to(torch::kFloat32));
    return parts;
  }())};
  wait_for(state_->group->broadcast(flat), options_, "broadcast of the initial weights");
  int64_t offset = 0;
  for (auto& t : tensors) {
    t.detach().copy_(flat[0].narrow(0, offset, t.numel()).view_as(t));
    offset += t.numel();
  }
}

void DataParallel::average_gradients(const std::vector<torch::Tensor>& parameters) {
  torch::NoGradGuard g;
  const auto t0 = std::chrono::steady_clock::now();
  const int64_t bucket = std::max<int64_t>(1, static_cast<int64_t>(options_.bucket_mb * (1 << 20) / 4));
  std::vector<torch::Tensor> grads;
  // A trainable parameter this rank's batch did not reach (one no loss term reached) gets
  // a zero gradient, so every rank sends the same list and the mean counts this rank's zero.
  for (auto p : parameters) {
    if (!p.grad().defined() && p.requires_grad()) p.mutable_grad() = torch::zeros_like(p);
    if (p.grad().defined()) grads.push_back(p.grad());
  }
  bytes_ = 0;
  // Consecutive gradients fill buckets of about bucket_mb; each bucket is one all-reduce of a flat copy.
  for (size_t first = 0; first < grads.size();) {
    size_t last = first;
    int64_t n = 0;
    while (last < grads.size() && (n == 0 || n + grads[last].numel() <= bucket)) n += grads[last++].numel();
    std::vector<torch::Tensor> parts;
    for (size_t k = first; k < last; ++k) parts.push_back(grads[k].reshape(-1));
    std::vector<torch::Tensor> flat = {torch::cat(parts)};
    wait_for(state_->group->allreduce(flat), options_, "gradient all-reduce");
    flat[0].div_(static_cast<double>(options_.world_size));
    int64_t offset = 0;
    for (size_t k = first; k < last; ++k) {
      grads[k].copy_(flat[0].narrow(0, offset, grads[k].numel()).view_as(grads[k]));
      offset += grads[k].numel();
    }
    bytes_ += n * static_cast<int64_t>(sizeof(float));
    first = last;
  }
  last_ms_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

std::vector<double> DataParallel::sum(const std::vector<double>& values) {
  std::vector<torch::Tensor> t = {torch::tensor(values, torch::kFloat64)};
  wait_for(state_->group->allreduce(t), options_, "all-reduce");
  return std::vector<double>(t[0].data_ptr<double>(), t[0].data_ptr<double>() + t[0].numel());
}

}  // namespace isplat
