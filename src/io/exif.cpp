// Minimal TIFF/EXIF walk: IFD0 -> Exif IFD -> focal length tags, both byte orders.
#include "io/exif.h"

#include <algorithm>
#include <cstdint>

namespace isplat {
namespace {

struct Tiff {
  const std::string& b;
  size_t base;
  bool little;
  bool ok(size_t off, size_t n) const { return base + off + n <= b.size(); }
  uint32_t u16(size_t off) const {
    const auto p = reinterpret_cast<const unsigned char*>(b.data() + base + off);
    return little ? p[0] | (p[1] << 8) : (p[0] << 8) | p[1];
  }
  uint32_t u32(size_t off) const {
    const auto p = reinterpret_cast<const unsigned char*>(b.data() + base + off);
    return little ? p[0] | (p[1] << 8) | (p[2] << 16) | (uint32_t(p[3]) << 24)
                  : (uint32_t(p[0]) << 24) | (p[1] << 16) | (p[2] << 8) | p[3];
  }
};

// Calls f(tag, type, count, value_offset_field) for each entry of the IFD at `off`.
template <class F>
void walk_ifd(const Tiff& t, size_t off, F f) {
  if (!t.ok(off, 2)) return;
  const uint32_t n = t.u16(off);
  for (uint32_t i = 0; i < n; ++i) {
    const size_t e = off + 2 + 12 * i;
    if (!t.ok(e, 12)) return;
    f(t.u16(e), t.u16(e + 2), t.u32(e + 4), e + 8);
  }
}

}  // namespace

ExifFocal read_exif_focal(const std::string& b) {
  ExifFocal out;
  if (b.size() < 4 || static_cast<unsigned char>(b[0]) != 0xFF || static_cast<unsigned char>(b[1]) != 0xD8) return out;
  size_t pos = 2;
  while (pos + 4 <= b.size() && static_cast<unsigned char>(b[pos]) == 0xFF) {
    const unsigned marker = static_cast<unsigned char>(b[pos + 1]);
    const size_t len = (static_cast<unsigned char>(b[pos + 2]) << 8) | static_cast<unsigned char>(b[pos + 3]);
    if (marker == 0xDA || len < 2) break;  // start of scan: no more metadata
    if (marker == 0xE1 && pos + 10 <= b.size() && b.compare(pos + 4, 6, std::string("Exif\0\0", 6)) == 0) {
      const size_t base = pos + 10;
      if (base + 8 > b.size()) return out;
      const bool little = b[base] == 'I';
      Tiff t{b, base, little};
      if (t.u16(2) != 42) return out;
      size_t exif_ifd = 0;
      walk_ifd(t, t.u32(4), [&](uint32_t tag, uint32_t, uint32_t, size_t v) {
        if (tag == 0x8769) exif_ifd = t.u32(v);
      });
      if (!exif_ifd) return out;
      walk_ifd(t, exif_ifd, [&](uint32_t tag, uint32_t type, uint32_t, size_t v) {
        if (tag == 0xA405 && type == 3) {
          const double f = t.u16(v);
          if (f > 0) out.focal_35mm = f;
        }
        if (tag == 0x920A && type == 5) {
          const size_t off = t.u32(v);
          if (t.ok(off, 8) && t.u32(off + 4) != 0) out.focal_mm = static_cast<double>(t.u32(off)) / t.u32(off + 4);
        }
      });
      return out;
    }
    pos += 2 + len;
  }
  return out;
}

double fx_from_35mm(double focal_35mm, int width, int height) {
  return focal_35mm / 36.0 * std::max(width, height);
}

}  // namespace isplat
