// .splat and .spz encoding: float32 tensors in, packed bytes out (and .spz back), zlib for the gzip layer.
#include "export/splat_formats.h"

#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include <torch/torch.h>

#include "core/error.h"
#include "core/log.h"
#include "geometry/color.h"
#include "io/atomic_file.h"
#include "io/ply.h"

namespace isplat {
namespace {

constexpr uint32_t kSpzMagic = 0x5053474e;  // "NGSP"
constexpr uint32_t kSpzVersion = 2;
constexpr int kSpzFractionalBits = 12;
constexpr double kSpzColorScale = 0.15;        // SH DC is stored scaled by this (room for out-of-gamut DC)
constexpr int64_t kSpzReaderLimit = 10000000;  // Niantic's loader refuses files with more Gaussians
constexpr size_t kSpzHeaderBytes = 16;

// Float32, contiguous, checked copies of one Gaussian set: sRGB colours, unit quaternions (w,x,y,z).
struct Packed {
  torch::Tensor means, scales, quats, srgb, opacities;
  int64_t count = 0;
};

Packed prepare(const std::string& path, const Gaussians& g_in, bool colors_linear) {
  ISPLAT_CHECK(!g_in.batched(), path, ": takes one (unbatched) Gaussian set");
  const Gaussians g = g_in.detach().to(torch::kFloat32);
  Packed p;
  p.count = g.count();
  p.means = g.means.contiguous();
  p.scales = g.scales.contiguous();
  p.quats = (g.quats / torch::clamp_min(g.quats.norm(2, 1, true), 1e-12)).contiguous();
  p.srgb = torch::clamp(colors_linear ? linear_to_srgb(g.colors) : g.colors, 0.0, 1.0).contiguous();
  p.opacities = torch::clamp(g.opacities, 0.0, 1.0).contiguous();
  for (const auto* t : {&p.means, &p.scales, &p.quats, &p.srgb, &p.opacities})
    ISPLAT_CHECK(torch::isfinite(*t).all().item<bool>(), path, ": Gaussians have non-finite values; not written");
  ISPLAT_CHECK((p.scales > 0).all().item<bool>(), path, ": Gaussians have scales <= 0; not written");
  return p;
}

uint8_t to_byte(double v) {
  return static_cast<uint8_t>(std::clamp(std::round(v), 0.0, 255.0));
}

template <class T>
void put(std::string& out, T v) {
  out.append(reinterpret_cast<const char*>(&v), sizeof(T));
}

std::string gzip(const std::string& path, const std::string& raw) {
  z_stream zs{};
  // 16 + MAX_WBITS asks zlib for a gzip wrapper rather than a zlib one (what .spz readers expect).
  ISPLAT_CHECK(deflateInit2(&zs, Z_BEST_COMPRESSION, Z_DEFLATED, 16 + MAX_WBITS, 8, Z_DEFAULT_STRATEGY) == Z_OK, path,
               ": zlib deflateInit2 failed");
  std::string out(deflateBound(&zs, raw.size()), '\0');
  zs.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(raw.data()));
  zs.avail_in = static_cast<uInt>(raw.size());
  zs.next_out = reinterpret_cast<Bytef*>(out.data());
  zs.avail_out = static_cast<uInt>(out.size());
  const int rc = deflate(&zs, Z_FINISH);
  out.resize(zs.total_out);
  deflateEnd(&zs);
  ISPLAT_CHECK(rc == Z_STREAM_END, path, ": zlib deflate failed (code ", rc, ")");
  return out;
}

// Our OpenCV frame (x right, y down, z forward) <-> SPZ's RUB (x right, y up, z back): negate y and z.
// This is a 180-degree turn about x (a rotation, not a mirror), so quaternions turn as (w, x, -y, -z).
constexpr float kRdfToRub[3] = {1.0f, -1.0f, -1.0f};

}  // namespace

std::string gunzip(const std::string& path, const std::string& packed) {
  z_stream zs{};
  ISPLAT_CHECK(inflateInit2(&zs, 16 + MAX_WBITS) == Z_OK, path, ": zlib inflateInit2 failed");
  zs.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(packed.data()));
  zs.avail_in = static_cast<uInt>(packed.size());
  std::string out;
  char buf[1 << 16];
  int rc = Z_OK;
  while (rc == Z_OK) {
    zs.next_out = reinterpret_cast<Bytef*>(buf);
    zs.avail_out = sizeof(buf);
    rc = inflate(&zs, Z_NO_FLUSH);
    out.append(buf, sizeof(buf) - zs.avail_out);
  }
  inflateEnd(&zs);
  ISPLAT_CHECK(rc == Z_STREAM_END, path, ": not a valid gzip stream (zlib code ", rc, ")");
  return out;
}

void write_splat(const std::string& path, const Gaussians& g, bool colors_linear) {
  const Packed p = prepare(path, g, colors_linear);
  const float* mean = p.means.data_ptr<float>();
  const float* scale = p.scales.data_ptr<float>();
  const float* quat = p.quats.data_ptr<float>();
  const float* rgb = p.srgb.data_ptr<float>();
  const float* alpha = p.opacities.data_ptr<float>();
  std::string out;
  out.reserve(static_cast<size_t>(p.count) * 32);
  for (int64_t i = 0; i < p.count; ++i) {
    for (int a = 0; a < 3; ++a) put<float>(out, mean[3 * i + a]);
    for (int a = 0; a < 3; ++a) put<float>(out, scale[3 * i + a]);
    for (int c = 0; c < 3; ++c) put<uint8_t>(out, to_byte(rgb[3 * i + c] * 255.0));
    put<uint8_t>(out, to_byte(alpha[i] * 255.0));
    for (int c = 0; c < 4; ++c) put<uint8_t>(out, to_byte(quat[4 * i + c] * 128.0 + 128.0));
  }
  write_file_atomic(path, out);
}

void write_spz(const std::string& path, const Gaussians& g, bool colors_linear) {
  const Packed p = prepare(path, g, colors_linear);
  const int64_t n = p.count;
  if (n > kSpzReaderLimit)
    log_warn(path, ": ", n, " Gaussians; Niantic's reference loader refuses more than ", kSpzReaderLimit);
  const float* mean = p.means.data_ptr<float>();
  const float* scale = p.scales.data_ptr<float>();
  const float* quat = p.quats.data_ptr<float>();
  const float* rgb = p.srgb.data_ptr<float>();
  const float* alpha = p.opacities.data_ptr<float>();
  std::string raw;
  raw.reserve(kSpzHeaderBytes + static_cast<size_t>(n) * 19);
  put<uint32_t>(raw, kSpzMagic);
  put<uint32_t>(raw, kSpzVersion);
  put<uint32_t>(raw, static_cast<uint32_t>(n));
  put<uint8_t>(raw, 0);  // SH degree: we have colour only
  put<uint8_t>(raw, kSpzFractionalBits);
  put<uint8_t>(raw, 0);  // flags: not trained with antialiasing, no extensions
  put<uint8_t>(raw, 0);  // reserved
  const double fixed_scale = 1 << kSpzFractionalBits;
  const int32_t fixed_limit = (1 << 23) - 1;
  for (int64_t i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a) {
      const double v = std::round(kRdfToRub[a] * mean[3 * i + a] * fixed_scale);
      if (std::abs(v) > fixed_limit)
        fail(path, ": Gaussian ", i, " has coordinate ", a, " = ", mean[3 * i + a], " m, outside the .spz range of +-",
             fixed_limit / fixed_scale, " m; re-centre or scale the scene");
      const int32_t fixed = static_cast<int32_t>(v);
      for (int b = 0; b < 3; ++b) raw.push_back(static_cast<char>((fixed >> (8 * b)) & 0xff));
    }
  for (int64_t i = 0; i < n; ++i) put<uint8_t>(raw, to_byte(alpha[i] * 255.0));
  for (int64_t i = 0; i < 3 * n; ++i)
    put<uint8_t>(raw, to_byte((rgb[i] - 0.5) / kShC0 * (kSpzColorScale * 255.0) + 127.5));
  for (int64_t i = 0; i < 3 * n; ++i) put<uint8_t>(raw, to_byte((std::log(scale[i]) + 10.0) * 16.0));
  for (int64_t i = 0; i < n; ++i) {
    const float* q = quat + 4 * i;
    // q and -q are the same rotation; w >= 0 lets the reader recover w from x, y, z.
    const double sign = q[0] < 0 ? -1.0 : 1.0;
    for (int a = 0; a < 3; ++a) put<uint8_t>(raw, to_byte(sign * kRdfToRub[a] * q[1 + a] * 127.5 + 127.5));
  }
  write_file_atomic(path, gzip(path, raw));
}

Gaussians read_spz(const std::string& path, bool want_linear) {
  const std::string raw = gunzip(path, read_file_bytes(path));
  ISPLAT_CHECK(raw.size() >= kSpzHeaderBytes, path, ": .spz too short for its 16-byte header");
  uint32_t magic, version, count;
  std::memcpy(&magic, raw.data(), 4);
  std::memcpy(&version, raw.data() + 4, 4);
  std::memcpy(&count, raw.data() + 8, 4);
  const int sh_degree = static_cast<uint8_t>(raw[12]), fractional_bits = static_cast<uint8_t>(raw[13]);
  const int flags = static_cast<uint8_t>(raw[14]);
  ISPLAT_CHECK(magic == kSpzMagic, path, ": not a .spz file (its first 4 bytes after gunzip are not \"NGSP\")");
  ISPLAT_CHECK(version == 2 || version == 3, path, ": .spz version ", version, " is not supported (2 and 3 are)");
  ISPLAT_CHECK(sh_degree <= 4, path, ": .spz SH degree ", sh_degree, " is not in 0..4");
  ISPLAT_CHECK(!(flags & 0x2), path, ": .spz extensions (flags 0x2) are not supported");
  const int64_t n = count;
  const int rotation_bytes = version >= 3 ? 4 : 3;
  const int sh_bytes = 3 * ((sh_degree + 1) * (sh_degree + 1) - 1);
  const size_t need = kSpzHeaderBytes + static_cast<size_t>(n) * (9 + 1 + 3 + 3 + rotation_bytes + sh_bytes);
  ISPLAT_CHECK(raw.size() >= need, path, ": truncated .spz: ", n, " Gaussians need ", need, " bytes, it has ",
               raw.size());
  const auto* bytes = reinterpret_cast<const uint8_t*>(raw.data());
  const uint8_t* positions = bytes + kSpzHeaderBytes;
  const uint8_t* alphas = positions + 9 * n;
  const uint8_t* colors = alphas + n;
  const uint8_t* scales = colors + 3 * n;
  const uint8_t* rotations = scales + 3 * n;

  auto means = torch::empty({n, 3}), scl = torch::empty({n, 3}), quats = torch::empty({n, 4});
  auto srgb = torch::empty({n, 3}), opac = torch::empty({n});
  float *m = means.data_ptr<float>(), *s = scl.data_ptr<float>(), *q = quats.data_ptr<float>();
  float *c = srgb.data_ptr<float>(), *o = opac.data_ptr<float>();
  const double inv_fixed = 1.0 / (1 << fractional_bits);
  for (int64_t i = 0; i < n; ++i) {
    for (int a = 0; a < 3; ++a) {
      const uint8_t* p = positions + 9 * i + 3 * a;
      int32_t fixed = p[0] | (p[1] << 8) | (p[2] << 16);
      if (fixed & 0x800000) fixed -= 1 << 24;  // sign-extend 24 bits
      m[3 * i + a] = static_cast<float>(kRdfToRub[a] * fixed * inv_fixed);
      s[3 * i + a] = static_cast<float>(std::exp(scales[3 * i + a] / 16.0 - 10.0));
      c[3 * i + a] = static_cast<float>((colors[3 * i + a] / 255.0 - 0.5) / kSpzColorScale * kShC0 + 0.5);
    }
    o[i] = static_cast<float>(alphas[i] / 255.0);
    double xyzw[4];
    const uint8_t* r = rotations + rotation_bytes * i;
    if (version >= 3) {
      // Smallest three: 2 bits name the largest component, three 10-bit fields (sign + 9-bit magnitude
      // scaled by 1/sqrt(2)) hold the others, the last component in the lowest bits.
      uint32_t packed = r[0] | (r[1] << 8) | (r[2] << 16) | (static_cast<uint32_t>(r[3]) << 24);
      const int largest = static_cast<int>(packed >> 30);
      double sum = 0;
      for (int k = 3; k >= 0; --k) {
        if (k == largest) continue;
        const double mag = (packed & 511u) / 511.0 * std::sqrt(0.5);
        xyzw[k] = (packed >> 9) & 1u ? -mag : mag;
        sum += xyzw[k] * xyzw[k];
        packed >>= 10;
      }
      xyzw[largest] = std::sqrt(std::max(0.0, 1.0 - sum));
    } else {
      double sum = 0;
      for (int a = 0; a < 3; ++a) {
        xyzw[a] = r[a] / 127.5 - 1.0;
        sum += xyzw[a] * xyzw[a];
      }
      xyzw[3] = std::sqrt(std::max(0.0, 1.0 - sum));
    }
    q[4 * i] = static_cast<float>(xyzw[3]);
    for (int a = 0; a < 3; ++a) q[4 * i + 1 + a] = static_cast<float>(kRdfToRub[a] * xyzw[a]);
  }
  srgb = torch::clamp(srgb, 0.0, 1.0);
  return {means, scl, quats / torch::clamp_min(quats.norm(2, 1, true), 1e-12),
          want_linear ? srgb_to_linear(srgb) : srgb, opac};
}

}  // namespace isplat
