// Checkpoint packing on top of safetensors.
#include "io/checkpoint.h"

#include <torch/torch.h>

#include "core/error.h"
#include "core/parse.h"
#include "io/safetensors.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>

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
    if (!mismatched.empty()) msg += "\n  shape mismatches: " + list(mismatched);
    fail(msg);
  }
  torch::NoGradGuard g;
  for (auto& [name, t] : ours) t.copy_(tensors.at(prefix + name).to(t.scalar_type()));
}

void load_module(const Checkpoint& ck, torch::nn::Module& module, const std::string& source,
                 const std::string& prefix) {
  load_named_tensors(module, ck.tensors, prefix, source + ": checkpoint does not fit the model built from its config.");
}

void save_checkpoint(const std::string& path, const Checkpoint& ck) {
  auto meta = ck.metadata;
  meta["format"] = kCheckpointFormat;
  write_safetensors(path, ck.tensors, meta);
}

Checkpoint load_checkpoint(const std::string& path) {
  SafeTensors st = read_safetensors(path);
  auto it = st.metadata.find("format");
  if (it == st.metadata.end() || it->second != kCheckpointFormat)
    fail(path, ": not an InfiniSplat checkpoint (metadata 'format' is '",
         it == st.metadata.end() ? std::string("<none>") : it->second, "', expected '", kCheckpointFormat, "')");
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
  fs::create_directories(dir_);
}

std::string CheckpointFolder::path(const std::string& name) const {
  return (fs::path(dir_) / (name + ".safetensors")).string();
}

void CheckpointFolder::save(const std::string& name, const Checkpoint& ck) {
  save_checkpoint(path(name), ck);
}

void CheckpointFolder::alias(const std::string& from, const std::string& to) {
  // Hard link under a temporary name, renamed into place: `to` is never missing or half-written.
  const fs::path file = path(from), target = path(to);
  const fs::path tmp = target.parent_path() / ("." + target.filename().string() + ".tmp");
  std::error_code ec;
  fs::remove(tmp, ec);
  fs::create_hard_link(file, tmp, ec);
  if (ec) fs::copy_file(file, tmp, fs::copy_options::overwrite_existing);
  fs::rename(tmp, target);
}

void CheckpointFolder::save_periodic(int64_t step, const Checkpoint& ck) {
  char name[32];
  std::snprintf(name, sizeof name, "step_%06lld", static_cast<long long>(step));
  save(name, ck);
  alias(name, "last");  // one file on disk for both names
  std::vector<fs::path> periodic;
  for (const auto& e : fs::directory_iterator(dir_)) {
    const std::string f = e.path().filename().string();
    if (f.rfind("step_", 0) == 0 && e.path().extension() == ".safetensors") periodic.push_back(e.path());
  }
  std::sort(periodic.begin(), periodic.end());
  while (static_cast<int64_t>(periodic.size()) > keep_last_) {
    fs::remove(periodic.front());  // last/best keep their own links
    periodic.erase(periodic.begin());
  }
}

}  // namespace isplat
