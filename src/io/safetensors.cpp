// safetensors format: validation on read (sizes, offsets, coverage), atomic write.
#include "io/safetensors.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <nlohmann/json.hpp>

#include <torch/torch.h>

#include "core/config.h"
#include "core/error.h"
#include "io/atomic_file.h"

namespace isplat {
namespace {

struct DtypeInfo {
  const char* name;
  torch::Dtype dtype;
  size_t size;
};

const DtypeInfo kDtypes[] = {
    {"F64", torch::kFloat64, 8},   {"F32", torch::kFloat32, 4}, {"F16", torch::kFloat16, 2},
    {"BF16", torch::kBFloat16, 2}, {"I64", torch::kInt64, 8},   {"I32", torch::kInt32, 4},
    {"I16", torch::kInt16, 2},     {"I8", torch::kInt8, 1},     {"U8", torch::kUInt8, 1},
    {"BOOL", torch::kBool, 1},
};

const DtypeInfo* by_name(const std::string& n) {
  for (const auto& d : kDtypes)
    if (n == d.name) return &d;
  return nullptr;
}

const DtypeInfo* by_dtype(torch::Dtype t) {
  for (const auto& d : kDtypes)
    if (t == d.dtype) return &d;
  return nullptr;
}

// Read-only memory map, unmapped on scope exit.
struct Mapped {
  const uint8_t* data = nullptr;
  size_t size = 0;
  explicit Mapped(const std::string& path) {
    int fd = ::open(path.c_str(), O_RDONLY);
    if (fd < 0) fail(path, ": cannot open: ", std::strerror(errno));
    struct stat st;
    if (fstat(fd, &st) != 0) {
      ::close(fd);
      fail(path, ": cannot stat");
    }
    size = static_cast<size_t>(st.st_size);
    if (size > 0) {
      void* p = mmap(nullptr, size, PROT_READ, MAP_PRIVATE, fd, 0);
      if (p == MAP_FAILED) {
        ::close(fd);
        fail(path, ": cannot map file");
      }
      data = static_cast<const uint8_t*>(p);
    }
    ::close(fd);
  }
  ~Mapped() {
    if (data) munmap(const_cast<uint8_t*>(data), size);
  }
};

}  // namespace

const torch::Tensor& SafeTensors::at(const std::string& name) const {
  auto it = tensors.find(name);
  if (it == tensors.end()) fail(source, ": no tensor named '", name, "'");
  return it->second;
}

SafeTensors read_safetensors(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) fail(path, ": no such file");
  Mapped file(path);
  if (file.size < 8) fail(path, ": truncated safetensors file (", file.size, " bytes, no header length)");
  uint64_t header_len = 0;
  for (int i = 7; i >= 0; --i) header_len = (header_len << 8) | file.data[i];
  if (header_len == 0 || header_len > file.size - 8 || header_len > (100u << 20))
    fail(path, ": corrupt safetensors header length ", header_len, " for a ", file.size, "-byte file");
  const nlohmann::json header =
      parse_json(std::string(reinterpret_cast<const char*>(file.data) + 8, header_len), path + " (safetensors header)");
  if (!header.is_object()) fail(path, ": safetensors header must be a JSON object");
  const uint8_t* data = file.data + 8 + header_len;
  const size_t data_size = file.size - 8 - header_len;

  SafeTensors out;
  out.source = path;
  std::vector<std::pair<size_t, size_t>> spans;
  for (auto it = header.begin(); it != header.end(); ++it) {
    const std::string& name = it.key();
    const auto& e = it.value();
    if (name == "__metadata__") {
      if (!e.is_object()) fail(path, ": __metadata__ must be an object of strings");
      for (auto m = e.begin(); m != e.end(); ++m) {
        if (!m.value().is_string()) fail(path, ": __metadata__ value for '", m.key(), "' is not a string");
        out.metadata[m.key()] = m.value().get<std::string>();
      }
      continue;
    }
    if (!e.is_object() || !e.contains("dtype") || !e.contains("shape") || !e.contains("data_offsets"))
      fail(path, ": tensor '", name, "' lacks dtype/shape/data_offsets");
    if (!e["dtype"].is_string()) fail(path, ": tensor '", name, "' dtype is not a string");
    const DtypeInfo* dt = by_name(e["dtype"].get<std::string>());
    if (!dt) fail(path, ": tensor '", name, "' has unsupported dtype ", e["dtype"].dump());
    std::vector<int64_t> shape;
    uint64_t numel = 1;
    if (!e["shape"].is_array()) fail(path, ": tensor '", name, "' shape is not a list");
    for (const auto& d : e["shape"]) {
      // A dimension beyond int64 or a product that wraps around would pass the size check below.
      if (!d.is_number_unsigned() || d.get<uint64_t>() > static_cast<uint64_t>(INT64_MAX))
        fail(path, ": tensor '", name, "' has a bad dimension ", d.dump());
      shape.push_back(d.get<int64_t>());
      if (__builtin_mul_overflow(numel, d.get<uint64_t>(), &numel) || numel > static_cast<uint64_t>(INT64_MAX))
        fail(path, ": tensor '", name, "' shape ", e["shape"].dump(), " has more elements than fit in 64 bits");
    }
    uint64_t need = 0;
    if (__builtin_mul_overflow(numel, static_cast<uint64_t>(dt->size), &need))
      fail(path, ": tensor '", name, "' shape ", e["shape"].dump(), " needs more bytes than fit in 64 bits");
    const auto& off = e["data_offsets"];
    if (!off.is_array() || off.size() != 2 || !off[0].is_number_unsigned() || !off[1].is_number_unsigned())
      fail(path, ": tensor '", name, "' data_offsets must be [begin, end]");
    const size_t begin = off[0].get<size_t>(), end = off[1].get<size_t>();
    if (begin > end || end > data_size)
      fail(path, ": tensor '", name, "' data [", begin, ", ", end, ") lies outside the ", data_size,
           "-byte data section (truncated file?)");
    if (end - begin != need)
      fail(path, ": tensor '", name, "' has ", end - begin, " bytes (at byte ", 8 + header_len + begin,
           ") but shape and dtype need ", need);
    spans.emplace_back(begin, end);
    torch::Tensor t;
    try {
      t = torch::empty(shape, torch::TensorOptions().dtype(dt->dtype));
    } catch (const c10::Error& err) {
      fail(path, ": tensor '", name, "' shape ", e["shape"].dump(), " is unusable: ", err.what_without_backtrace());
    }
    if (numel > 0) std::memcpy(t.data_ptr(), data + begin, end - begin);
    out.tensors.emplace(name, t);
  }
  std::sort(spans.begin(), spans.end());
  size_t cursor = 0;
  for (const auto& s : spans) {
    if (s.first < cursor) fail(path, ": tensors overlap in the data section");
    if (s.first > cursor)
      fail(path, ": gap in the data section at byte ", 8 + header_len + cursor, " (corrupt header)");
    cursor = s.second;
  }
  if (cursor != data_size) fail(path, ": data section has ", data_size - cursor, " unindexed trailing bytes");
  return out;
}

void write_safetensors(const std::string& path, const std::map<std::string, torch::Tensor>& tensors,
                       const std::map<std::string, std::string>& metadata) {
  nlohmann::json header = nlohmann::json::object();
  if (!metadata.empty()) header["__metadata__"] = metadata;
  std::vector<torch::Tensor> ordered;
  size_t offset = 0;
  for (const auto& [name, tensor] : tensors) {
    ISPLAT_CHECK(name != "__metadata__", path, ": '__metadata__' is reserved");
    const DtypeInfo* dt = by_dtype(tensor.scalar_type());
    ISPLAT_CHECK(dt, path, ": tensor '", name, "' has unsupported dtype ", tensor.scalar_type());
    auto t = tensor.detach().to(torch::kCPU).contiguous();
    const size_t bytes = static_cast<size_t>(t.numel()) * dt->size;
    header[name] = {{"dtype", dt->name}, {"shape", t.sizes().vec()}, {"data_offsets", {offset, offset + bytes}}};
    offset += bytes;
    ordered.push_back(t);
  }
  std::string text = header.dump();
  text.append((8 - text.size() % 8) % 8, ' ');
  write_file_atomic(path, [&](std::ostream& os) {
    uint64_t n = text.size();
    char len[8];
    for (int i = 0; i < 8; ++i) len[i] = static_cast<char>((n >> (8 * i)) & 0xFF);
    os.write(len, 8);
    os.write(text.data(), static_cast<std::streamsize>(text.size()));
    for (const auto& t : ordered)
      os.write(static_cast<const char*>(t.data_ptr()), static_cast<std::streamsize>(t.numel() * t.element_size()));
  });
}

}  // namespace isplat
