// 3DGS PLY: header with typed properties, little-endian binary payload.
#include "io/ply.h"

#include <torch/torch.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

#include "core/error.h"
#include "core/log.h"
#include "geometry/color.h"
#include "io/atomic_file.h"

namespace isplat {
namespace {

const char* kProps[] = {"x",       "y",       "z",       "nx",      "ny",    "nz",    "f_dc_0", "f_dc_1", "f_dc_2",
                        "opacity", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1", "rot_2",  "rot_3"};

// Property types, resolved once from the header so the per-vertex loop does not compare strings.
enum class PlyType { F32, F64, U8, I8, I16, U16, I32, U32 };

struct PlyTypeName {
  const char* name;
  PlyType type;
  size_t size;
};
constexpr PlyTypeName kTypes[] = {
    {"float", PlyType::F32, 4}, {"float32", PlyType::F32, 4}, {"double", PlyType::F64, 8}, {"float64", PlyType::F64, 8},
    {"uchar", PlyType::U8, 1},  {"uint8", PlyType::U8, 1},    {"char", PlyType::I8, 1},    {"int8", PlyType::I8, 1},
    {"short", PlyType::I16, 2}, {"int16", PlyType::I16, 2},   {"ushort", PlyType::U16, 2}, {"uint16", PlyType::U16, 2},
    {"int", PlyType::I32, 4},   {"int32", PlyType::I32, 4},   {"uint", PlyType::U32, 4},   {"uint32", PlyType::U32, 4}};

const PlyTypeName* find_type(const std::string& t) {
  for (const auto& k : kTypes)
    if (t == k.name) return &k;
  return nullptr;
}

template <class T>
double load(const char* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return static_cast<double>(v);
}

double read_value(const char* p, PlyType t) {
  switch (t) {
    case PlyType::F32:
      return load<float>(p);
    case PlyType::F64:
      return load<double>(p);
    case PlyType::U8:
      return load<uint8_t>(p);
    case PlyType::I8:
      return load<int8_t>(p);
    case PlyType::I16:
      return load<int16_t>(p);
    case PlyType::U16:
      return load<uint16_t>(p);
    case PlyType::I32:
      return load<int32_t>(p);
    case PlyType::U32:
      return load<uint32_t>(p);
  }
  return 0;
}

// Largest log-scale whose exponential is finite in float (exp(88.72) = FLT_MAX).
constexpr float kMaxLogScale = 88.7f;

// Where the header ends: the first line that is exactly "end_header" (a comment may contain the word), and where
// the binary data starts after it.
struct PlyHeader {
  size_t end = 0, data = 0;
};

PlyHeader find_header(const std::string& bytes, const std::string& path) {
  if (bytes.compare(0, 4, "ply\n") != 0 && bytes.compare(0, 5, "ply\r\n") != 0)
    fail(path, ": not a PLY file (no ply/end_header)");
  for (size_t line = 0; line < bytes.size();) {
    const size_t eol = bytes.find('\n', line);
    if (eol == std::string::npos) break;
    const size_t len = eol - line - (eol > line && bytes[eol - 1] == '\r' ? 1 : 0);
    if (bytes.compare(line, len, "end_header") == 0 && len == 10) return {line, eol + 1};
    line = eol + 1;
  }
  fail(path, ": not a PLY file (no ply/end_header)");
}

}  // namespace

void write_ply(const std::string& path, const Gaussians& g_in, bool colors_linear, const PlyOptions& options) {
  ISPLAT_CHECK(!g_in.batched(), path, ": write_ply takes one (unbatched) Gaussian set");
  ISPLAT_CHECK(options.sh_degree >= 0 && options.sh_degree <= 3, path, ": PLY sh_degree ", options.sh_degree,
               " is not in 0..3");
  const Gaussians g = g_in.detach().to(torch::kFloat32);
  const int64_t N = g.count();
  const int64_t rest = 3 * ((options.sh_degree + 1) * (options.sh_degree + 1) - 1);
  auto colors = colors_linear ? linear_to_srgb(g.colors) : g.colors;
  // What the reader refuses is never written: a zero quaternion has no rotation.
  const int64_t zero_quats = (g.quats.norm(2, 1) < 1e-10).sum().item<int64_t>();
  ISPLAT_CHECK(zero_quats == 0, path, ": ", zero_quats, " Gaussians have a zero quaternion; not written");
  auto quats = g.quats / torch::clamp_min(g.quats.norm(2, 1, true), 1e-12);
  auto opac = torch::clamp(g.opacities, 1e-6, 1 - 1e-6);
  auto cols =
      torch::cat({g.means, torch::zeros({N, 3}), (colors - 0.5) / kShC0, torch::zeros({N, rest}),
                  torch::log(opac / (1 - opac)).unsqueeze(1), torch::log(torch::clamp_min(g.scales, 1e-12)), quats},
                 1)
          .contiguous();
  ISPLAT_CHECK(torch::isfinite(cols).all().item<bool>(), path, ": Gaussians have non-finite values; not written");
  std::ostringstream header;
  header << "ply\nformat binary_little_endian 1.0\ncomment " << kPlyWriterComment << "\n";
  for (const std::string& c : options.comments) {
    ISPLAT_CHECK(c.find_first_of("\r\n") == std::string::npos, path, ": PLY comment '", c, "' has a line break");
    header << "comment " << c << "\n";
  }
  header << "element vertex " << N << "\n";
  for (int k = 0; k < 17; ++k) {
    header << "property float " << kProps[k] << "\n";
    if (k == 8)  // the higher SH bands follow the DC term in the 3DGS layout
      for (int64_t r = 0; r < rest; ++r) header << "property float f_rest_" << r << "\n";
  }
  header << "end_header\n";
  write_file_atomic(path, [&](std::ostream& os) {
    const std::string h = header.str();
    os.write(h.data(), static_cast<std::streamsize>(h.size()));
    os.write(static_cast<const char*>(cols.data_ptr()), static_cast<std::streamsize>(cols.numel() * sizeof(float)));
  });
}

Gaussians read_ply(const std::string& path, bool want_linear) {
  ErrorContext context("reading the PLY ", path);
  const std::string bytes = read_file_bytes(path);
  const PlyHeader header = find_header(bytes, path);
  const size_t end = header.end;
  std::istringstream hs(bytes.substr(0, end));
  std::string line, format;
  int64_t n = -1;
  bool in_vertex = false;
  std::vector<std::pair<std::string, const PlyTypeName*>> props;
  while (std::getline(hs, line)) {
    std::istringstream ls(line);
    std::string word;
    ls >> word;
    if (word == "format") {
      ls >> format;
    } else if (word == "element") {
      std::string name;
      int64_t count = -1;
      if (!(ls >> name >> count) || count < 0) fail(path, ": bad element line '", line, "'");
      in_vertex = name == "vertex";
      if (in_vertex)
        n = count;
      else if (count > 0)
        fail(path, ": unsupported element '", name, "' before or after the vertices");
    } else if (word == "property" && in_vertex) {
      std::string type, name;
      ls >> type;
      if (type == "list") fail(path, ": list properties are not supported in the vertex element");
      ls >> name;
      const PlyTypeName* t = find_type(type);
      if (!t) fail(path, ": property '", name, "' has unknown type '", type, "'");
      props.emplace_back(name, t);
    }
  }
  if (format != "binary_little_endian")
    fail(path, ": format '", format, "' is not supported (binary_little_endian only)");
  if (n < 0) fail(path, ": no vertex element");
  std::vector<int> col(17, -1);
  std::vector<size_t> offset(props.size());
  size_t stride = 0;
  for (size_t i = 0; i < props.size(); ++i) {
    offset[i] = stride;
    stride += props[i].second->size;
    for (int k = 0; k < 17; ++k)
      if (props[i].first == kProps[k]) col[k] = static_cast<int>(i);
  }
  for (int k = 0; k < 17; ++k)
    if (col[k] < 0 && (k < 3 || k > 5)) fail(path, ": missing property '", kProps[k], "' (3DGS layout)");
  const size_t data = header.data;
  // Divide rather than multiply: a declared count such as 2^62 must not wrap around the size check.
  if (static_cast<uint64_t>(n) > (bytes.size() - data) / stride)
    fail(path, ": truncated: ", n, " vertices of ", stride, " bytes each do not fit in the ", bytes.size() - data,
         " bytes after the header (at byte ", data, ")");
  // Data after the declared vertices: another writer's element, or a count that lost vertices. Not an error (the
  // declared ones read whole), but said, with the size, so a cut-down scene is never taken for the whole one.
  if (const size_t extra = bytes.size() - data - static_cast<size_t>(n) * stride; extra > 0)
    log_warn(path, ": ", extra, " bytes (", extra / stride, " vertices' worth) after the ", n,
             " declared vertices are ignored");
  auto out = torch::empty({n, 17});
  float* o = out.data_ptr<float>();
  for (int64_t v = 0; v < n; ++v) {
    const char* rec = bytes.data() + data + v * stride;
    for (int k = 0; k < 17; ++k) {
      const float x =
          col[k] < 0 ? 0.0f : static_cast<float>(read_value(rec + offset[col[k]], props[col[k]].second->type));
      if (!std::isfinite(x))
        fail(path, ": vertex ", v, " property '", kProps[k], "' is not finite (at byte ",
             data + v * stride + offset[col[k]], ")");
      // Log-scales: exp() above ~88.7 is infinite in float, a Gaussian covering all space.
      if (k >= 10 && k <= 12 && x > kMaxLogScale)
        fail(path, ": vertex ", v, " property '", kProps[k], "' = ", x, " is a log-scale whose exponential overflows",
             " (largest ", kMaxLogScale, ")");
      o[v * 17 + k] = x;
    }
    const float* q = o + v * 17 + 13;  // a zero quaternion has no rotation to normalize to
    if (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3] < 1e-20f)
      fail(path, ": vertex ", v, " has a zero rotation quaternion (rot_0..rot_3)");
  }
  Gaussians g;
  g.means = out.narrow(1, 0, 3).contiguous();
  auto srgb = torch::clamp(out.narrow(1, 6, 3) * kShC0 + 0.5, 0.0, 1.0);
  g.colors = (want_linear ? srgb_to_linear(srgb) : srgb).contiguous();
  g.opacities = torch::sigmoid(out.select(1, 9)).contiguous();
  g.scales = torch::exp(out.narrow(1, 10, 3)).contiguous();
  g.quats = out.narrow(1, 13, 4).contiguous();
  return g;
}

std::vector<std::string> read_ply_comments(const std::string& path) {
  const std::string bytes = read_file_bytes(path);
  std::istringstream hs(bytes.substr(0, find_header(bytes, path).end));
  std::vector<std::string> comments;
  std::string line;
  while (std::getline(hs, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.rfind("comment ", 0) == 0) comments.push_back(line.substr(8));
  }
  return comments;
}

}  // namespace isplat
