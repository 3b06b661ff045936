// Gaussians as the standard 3DGS PLY (binary little-endian): x y z nx ny nz f_dc_0..2 opacity scale_0..2
// rot_0..3, with log-scale, logit-opacity and SH-DC colour, as 3DGS viewers read it.
#pragma once
#include <string>

#include <torch/types.h>

#include "core/gaussians.h"

namespace isplat {

constexpr double kShC0 = 0.28209479177387814;

// Writes unbatched Gaussians. Colours are written as SH DC of sRGB colour ((c - 0.5) / C0), because
// 3DGS viewers composite in the space of their colours; `colors_linear` says what `g.colors` holds.
void write_ply(const std::string& path, const Gaussians& g, bool colors_linear = true);

// Reads a 3DGS PLY (extra properties such as f_rest_* or normals are skipped). Returns activated values
// with colours converted to linear RGB when `want_linear`. Malformed or truncated files throw Error.
Gaussians read_ply(const std::string& path, bool want_linear = true);

// Keeps Gaussians with opacity >= min_opacity; returns the number removed.
int64_t prune_by_opacity(Gaussians& g, double min_opacity);

}  // namespace isplat
