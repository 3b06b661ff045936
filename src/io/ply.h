// Gaussians as the standard 3DGS PLY (binary little-endian): x y z nx ny nz f_dc_0..2 [f_rest_*] opacity scale_0..2
// rot_0..3, with log-scale, logit-opacity and SH-DC colour, as 3DGS viewers read it.
#pragma once
#include <string>
#include <vector>

#include <torch/types.h>

#include "core/gaussians.h"

namespace isplat {

constexpr double kShC0 = 0.28209479177387814;
// The comment line write_ply always writes first (without the leading "comment ").
constexpr char kPlyWriterComment[] = "written by InfiniSplat-C++ (colours: SH DC of sRGB)";

// What the writer adds beyond the DC layout. Some viewers only open files whose SH degree is 3, so
// sh_degree > 0 writes the f_rest_* properties (3 * ((d + 1)^2 - 1) of them, 45 for degree 3) as zeros
// in the 3DGS order, between f_dc_2 and opacity.
// `comments` become header comment lines (one line each, no line breaks), such as what pruning removed.
struct PlyOptions {
  int sh_degree = 0;  // 0..3
  std::vector<std::string> comments;
};

// Writes unbatched Gaussians. Colours are written as SH DC of sRGB colour ((c - 0.5) / C0), because
// 3DGS viewers composite in the space of their colours; `colors_linear` says what `g.colors` holds.
void write_ply(const std::string& path, const Gaussians& g, bool colors_linear = true, const PlyOptions& options = {});

// Reads a 3DGS PLY (extra properties such as f_rest_* or normals are skipped). Returns activated values
// with colours converted to linear RGB when `want_linear`. Malformed or truncated files throw Error.
Gaussians read_ply(const std::string& path, bool want_linear = true);

// The header's comment lines, without the leading "comment ", in file order. Malformed headers throw Error.
std::vector<std::string> read_ply_comments(const std::string& path);

}  // namespace isplat
