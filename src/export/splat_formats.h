// Web splat formats written natively: antimatter15's .splat and Niantic's .spz (version 2), and a .spz reader.
#pragma once
#include <string>

#include <torch/types.h>

#include "core/gaussians.h"

namespace isplat {

// .splat: 32 bytes per Gaussian, no header, little-endian: position float32 x3, scale float32 x3 (linear
// metres), colour RGBA uint8 x4 (sRGB colour; alpha = opacity * 255), rotation uint8 x4 (normalized
// quaternion w,x,y,z, each round(q * 128 + 128) clamped to 0..255). Bytes are rounded to nearest.
// Gaussians keep their input order: the web viewer sorts by depth itself on every view change.
// Positions stay in our frame (OpenCV: x right, y down, z forward), the frame 3DGS PLY files use and the
// one antimatter15's viewer expects. `colors_linear` says what `g.colors` holds (as in write_ply).
void write_splat(const std::string& path, const Gaussians& g, bool colors_linear = true);

// .spz version 2: a gzip stream of a 16-byte header (magic 0x5053474e "NGSP", version 2, count, SH degree
// 0, 12 fractional bits, flags 0, reserved 0), then per attribute, all Gaussians at a time: positions
// (24-bit signed fixed point, 1/4096 m, so within +-2048 m), alphas (opacity * 255), colours (SH DC of
// sRGB * 0.15 * 255 + 127.5), scales ((ln s + 10) * 16, so 4.5e-5..380 m), rotations (x,y,z of the
// normalized quaternion with w >= 0, each q * 127.5 + 127.5). Every byte is rounded to nearest and clamped.
// SPZ stores RUB (x right, y up, z back, as OpenGL): positions are written as (x, -y, -z) and quaternions
// as (w, x, -y, -z), a 180-degree turn about x. Positions out of range throw Error naming the Gaussian.
void write_spz(const std::string& path, const Gaussians& g, bool colors_linear = true);

// Reads .spz versions 2 and 3 back into our frame (the inverse turn), activated values, colours in
// linear RGB when `want_linear`. Higher SH bands are skipped. Bad files throw Error naming the path.
Gaussians read_spz(const std::string& path, bool want_linear = true);

// The bytes inside a gzip stream (`path` names the source in errors); a corrupt stream is an Error.
std::string gunzip(const std::string& path, const std::string& packed);

}  // namespace isplat
