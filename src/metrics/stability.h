// Stability measures beyond PSNR/SSIM/LPIPS (the failure modes of single-image methods under large viewpoint
// changes): holes, cracks, and incoherent surface normals in a rendered target view.
#pragma once
#include <torch/types.h>

#include <string>

namespace isplat {

// Which broken pairs crack_rate counts, by the side the render errs to at the pair's deviant pixel (the one with the
// larger relative error of rendered against reference depth): a nearer surface drawn over it (a fringe, a floater, a
// silhouette drawn too wide) or a farther one seen through it (a tear, a silhouette drawn too narrow).
enum class CrackSide { any, nearer, farther };

// Which broken pairs crack_rate counts, by where their deviant pixel lies in the reference: on the near side of a
// reference depth edge within 2 px (a silhouette drawn too narrow or too wide there), on its far side (what a new view
// uncovers beside a silhouette, or a fringe over it), or either, including pixels with no edge that close.
enum class EdgeSide { any, near, far };

struct StabilityOptions {
  double hole_alpha = 0.5;    // a pixel is a hole when its rendered alpha stays below this
  double crack_jump = 0.05;   // rendered depth jump between neighbours, relative to depth, that makes a crack
  double smooth_jump = 0.01;  // ... where the reference depth changes by less than this (relative)
  double planar_deg = 2.0;    // reference normals of neighbours within this angle mark a planar surface
  int64_t edge_margin = 0;    // crack_rate skips pairs within this many pixels of a reference depth edge
  bool holes_break = false;   // crack_rate counts a pair with a hole on either side as broken, instead of skipping it
  CrackSide crack_side = CrackSide::any;  // crack_rate counts only the broken pairs that err to this side
  // crack_rate counts only the broken pairs whose deviant pixel's rendered depth errs by at least this share of the
  // reference (|z / z_ref − 1|; a hole counted by holes_break always does). 0 = every broken pair.
  double min_error = 0.0;
  EdgeSide edge_side = EdgeSide::any;  // crack_rate counts only the broken pairs whose deviant pixel lies on this side
};

// "any" | "nearer" | "farther"; anything else fails naming the value.
CrackSide parse_crack_side(const std::string& name);
// "any" | "near" | "far"; anything else fails naming the value.
EdgeSide parse_edge_side(const std::string& name);

// Share of masked pixels (mask [H,W] nonzero) whose alpha ([1,H,W] or [H,W]) is below options.hole_alpha.
// NaN when the mask is empty.
double hole_rate(const torch::Tensor& alpha, const torch::Tensor& mask, const StabilityOptions& options = {});

// Share of masked neighbour pairs (right and down) where the rendered depth (depth_sum / alpha, both
// rendered) jumps by more than crack_jump·z while the reference depth (ref_depth [H,W], valid where > 0 and
// finite) changes by less than smooth_jump·z; pairs where either pixel is a hole are not counted (hole_rate
// counts them), unless holes_break: then such a pair counts as broken, so a method cannot avoid cracks by
// leaving the gap empty. With edge_margin > 0, pairs with a pixel within that many pixels (Chebyshev) of a reference
// depth edge (a neighbour jump >= crack_jump·z, or valid next to invalid) are skipped too: what remains are
// cracks in surfaces, not silhouettes drawn a pixel or two off. crack_side splits the broken pairs by the side their
// deviant pixel errs to (the denominator stays every qualifying pair, so nearer + farther = any); a hole counted by
// holes_break errs farther (nothing is drawn there). min_error > 0 keeps only the breaks whose deviant pixel errs by
// at least that much: a large error is another surface seen, a small one the right surface slightly off or a blend
// of two at a soft edge. edge_side keeps the breaks whose deviant pixel's reference depth is on the near (far) side
// of a reference depth edge within 2 px: below (above) the geometric mean of the least and largest valid reference
// depths around it, where those differ by crack_jump or more. NaN when no pair qualifies.
double crack_rate(const torch::Tensor& depth_sum, const torch::Tensor& alpha, const torch::Tensor& ref_depth,
                  const torch::Tensor& mask, const StabilityOptions& options = {});

// Where crack_rate's pairs lie, as an image [3,H,W] in [0,1]: black where no pair is scored, grey on the pixels of
// the scored pairs, and on each broken pair's deviant pixel red where it errs farther (a surface seen through: a
// tear, a silhouette drawn too narrow, or a hole with holes_break) and blue where it errs nearer (a fringe drawn over
// it). A pixel deviant both ways is red. crack_side keeps only that side's breaks.
torch::Tensor crack_map(const torch::Tensor& depth_sum, const torch::Tensor& alpha, const torch::Tensor& ref_depth,
                        const torch::Tensor& mask, const StabilityOptions& options = {});

// Mean angle in degrees between the rendered normals (normal_sum [3,H,W], normalized here) of neighbouring
// pixels where the reference depth, seen through K [3,3], is planar (neighbouring reference normals within
// planar_deg) and neither pixel is a hole. 0 for a perfectly coherent surface; NaN when nothing qualifies.
double normal_incoherence_deg(const torch::Tensor& normal_sum, const torch::Tensor& alpha,
                              const torch::Tensor& ref_depth, const torch::Tensor& K, const torch::Tensor& mask,
                              const StabilityOptions& options = {});

}  // namespace isplat
