// Checkpoint packing on top of safetensors.
#include "io/checkpoint.h"

#include <torch/torch.h>
#include <zlib.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "core/error.h"
#include "core/log.h"
#include "core/parse.h"
#include "io/atomic_file.h"
#include "io/safetensors.h"

namespace isplat {

int64_t Checkpoint::step() const {
  auto it = metadata.find("step");
  if (it == metadata.end()) return 0;
  const auto v = parse_int(it->second);
  if (!v || *v < 0) fail("checkpoint: metadata 'step' is '", it->second, "', not a step count");
  return *v;
}

const std::string& Checkpoint::config_json() const {
  static const std::string empty = "{}";
  auto it = metadata.find("config");
  return it == metadata.end() ? empty : it->second;
}

void put_module(Checkpoint& ck, const torch::nn::Module& module, const std::string& prefix) {
  for (const auto& p : module.named_parameters(true)) ck.tensors[prefix + p.key()] = p.value().detach().clone();
  for (const auto& b : module.named_buffers(true)) ck.tensors[prefix + b.key()] = b.value().detach().clone();
}

void load_named_tensors(torch::nn::Module& module, const std::map<std::string, torch::Tensor>& tensors,
                        const std::string& prefix, const std::string& what,
                        const std::function<bool(const std::string&)>& ignorable) {
  std::map<std::string, torch::Tensor> ours;
  for (const auto& p : module.named_parameters(true)) ours[p.key()] = p.value();
  for (const auto& b : module.named_buffers(true)) ours[b.key()] = b.value();
  std::vector<std::string> missing, unexpected, mismatched;
  for (const auto& [name, t] : ours) {
    auto it = tensors.find(prefix + name);
    if (it == tensors.end())
      missing.push_back(name);
    else if (it->second.sizes() != t.sizes())
      mismatched.push_back(cat(name, " (file ", it->second.sizes(), ", model ", t.sizes(), ")"));
    else if (at::isFloatingType(it->second.scalar_type()) != at::isFloatingType(t.scalar_type()))
      // Float16 into float32 is a conversion; integers into weights are a corrupt or foreign file.
      mismatched.push_back(cat(name, " (file ", it->second.scalar_type(), ", model ", t.scalar_type(), ")"));
  }
  for (const auto& [key, t] : tensors) {
    if (key.rfind(prefix, 0) != 0) continue;
    const std::string name = key.substr(prefix.size());
    if (!ours.count(name) && !(ignorable && ignorable(name))) unexpected.push_back(name);
  }
  if (!missing.empty() || !unexpected.empty() || !mismatched.empty()) {
    auto list = [](const std::vector<std::string>& v) {
      std::string s;
      for (size_t i = 0; i < v.size() && i < 12; ++i) s += (i ? ", " : "") + v[i];
      return v.size() > 12 ? s + cat(", ... (", v.size(), " in all)") : s;
    };
    std::string msg = what;
    if (!missing.empty()) msg += "\n  missing keys: " + list(missing);
    if (!unexpected.empty()) msg += "\n  unexpected keys: " + list(unexpected);
    if (!mismatched.empty()) msg += "\n  shape or type mismatches: " + list(mismatched);
    fail(msg);
  }
  torch::NoGradGuard g;
  for (auto& [name, t] : ours) t.copy_(tensors.at(prefix + name).to(t.scalar_type()));
}

void load_module(const Checkpoint& ck, torch::nn::Module& module, const std::string& source,
                 const std::string& prefix) {
  load_named_tensors(module, ck.tensors, prefix, source + ": checkpoint does not fit the model built from its config.");
}

std::string tensors_checksum(const std::map<std::string, torch::Tensor>& tensors) {
  uLong crc = crc32_z(0L, Z_NULL, 0);
  auto add = [&](const void* p, size_t n) { crc = crc32_z(crc, static_cast<const Bytef*>(p), n); };
  for (const auto& [name, tensor] : tensors) {
    const auto t = tensor.detach().to(torch::kCPU).contiguous();
    const std::string head = cat(name, '\0', t.scalar_type(), '\0', t.sizes(), '\0');
    add(head.data(), head.size());
    add(t.data_ptr(), static_cast<size_t>(t.numel()) * t.element_size());
  }
  char hex[9];
  std::snprintf(hex, sizeof hex, "%08lx", static_cast<unsigned long>(crc & 0xFFFFFFFFul));
  return hex;
}

void save_checkpoint(const std::string& path, const Checkpoint& ck) {
  auto meta = ck.metadata;
  meta["format"] = kCheckpointFormat;
  meta["checksum"] = tensors_checksum(ck.tensors);
  write_safetensors(path, ck.tensors, meta);
}

Checkpoint load_checkpoint(const std::string& path) {
  ErrorContext context("loading the checkpoint ", path);
  SafeTensors st = read_safetensors(path);
  auto it = st.metadata.find("format");
  if (it == st.metadata.end() || it->second != kCheckpointFormat)
    fail(path, ": not an InfiniSplat checkpoint (metadata 'format' is '",
         it == st.metadata.end() ? std::string("<none>") : it->second, "', expected '", kCheckpointFormat, "')");
  auto sum = st.metadata.find("checksum");
  if (sum != st.metadata.end()) {
    const std::string actual = tensors_checksum(st.tensors);
    if (actual != sum->second)
      fail(path, ": checksum mismatch (metadata says ", sum->second, ", the tensors give ", actual,
           "): the file was damaged or edited after it was written");
  }
  return {std::move(st.tensors), std::move(st.metadata)};
}

torch::Tensor bytes_to_tensor(const std::string& bytes) {
  auto t = torch::empty({static_cast<int64_t>(bytes.size())}, torch::kUInt8);
  std::memcpy(t.data_ptr(), bytes.data(), bytes.size());
  return t;
}

std::string tensor_to_bytes(const torch::Tensor& t) {
  auto c = t.contiguous();
  return std::string(static_cast<const char*>(c.data_ptr()), static_cast<size_t>(c.numel()));
}

namespace fs = std::filesystem;

CheckpointFolder::CheckpointFolder(std::string dir, int64_t keep_last) : dir_(std::move(dir)), keep_last_(keep_last) {
  std::error_code ec;
  fs::create_directories(dir_, ec);
  if (ec) fail(dir_, ": cannot create the checkpoint folder: ", ec.message());
}

std::string CheckpointFolder::path(const std::string& name) const {
  return (fs::path(dir_) / (name + ".safetensors")).string();
}

void CheckpointFolder::save(const std::string& name, const Checkpoint& ck) {
  save_checkpoint(path(name), ck);
}

void CheckpointFolder::alias(const std::string& from, const std::string& to) {
  copy_file_atomic(path(from), path(to));
}

int64_t CheckpointFolder::remove_stale_temporaries() const {
  return isplat::remove_stale_temporaries(dir_);
}

void CheckpointFolder::save_periodic(int64_t step, const Checkpoint& ck) {
  char name[32];
  std::snprintf(name, sizeof name, "step_%06lld", static_cast<long long>(step));
  save(name, ck);
  alias(name, "last");
  std::vector<fs::path> periodic;
  for (const auto& e : fs::directory_iterator(dir_)) {
    const std::string f = e.path().filename().string();
    if (f.rfind("step_", 0) == 0 && e.path().extension() == ".safetensors") periodic.push_back(e.path());
  }
  std::sort(periodic.begin(), periodic.end());
  while (static_cast<int64_t>(periodic.size()) > keep_last_) {
    std::error_code ec;
    fs::remove(periodic.front(), ec);  // a failed removal costs disk, not state
    periodic.erase(periodic.begin());
  }
}

std::optional<CheckpointFolder::Found> CheckpointFolder::newest_intact() const {
  auto try_load = [](const std::string& p) -> std::optional<Found> {
    std::error_code ec;
    if (!fs::exists(p, ec)) return std::nullopt;
    try {
      Checkpoint ck = load_checkpoint(p);
      if (!ck.tensors.count("optim/state") || !ck.tensors.count("rng/torch"))
        fail(p, ": holds no optimizer or RNG state");
      return Found{p, std::move(ck)};
    } catch (const Error& e) {
      log_warn("train: passing over a checkpoint: ", e.what());  // the message names the file
      return std::nullopt;
    }
  };
  if (auto last = try_load(path("last"))) return last;
  // `last` is missing or damaged: the newest periodic file that loads, or `best` when it is newer.
  std::vector<std::string> periodic;
  std::error_code ec;
  for (fs::directory_iterator it(dir_, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string f = it->path().filename().string();
    if (f.rfind("step_", 0) == 0 && it->path().extension() == ".safetensors") periodic.push_back(it->path().string());
  }
  std::sort(periodic.rbegin(), periodic.rend());
  std::optional<Found> found;
  for (const auto& p : periodic)
    if ((found = try_load(p))) break;
  auto best = try_load(path("best"));
  if (best && (!found || best->checkpoint.step() > found->checkpoint.step())) found = std::move(best);
  if (found) log_warn("train: ", path("last"), " is missing or damaged; falling back to ", found->path);
  return found;
}

}  // namespace isplat
