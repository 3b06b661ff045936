// Raw CPU kernels of the splatting renderer (projection, tile binning, rasterization) and the constants and
// per-pixel rule shared by their forward and backward passes.
#pragma once
#include <torch/types.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace isplat::splat {

// One set of constants for both passes (DESIGN §3): changing one here changes forward and backward together.
constexpr double kAlphaMax = 0.99;                               // α = min(0.99, o·G)
constexpr double kAlphaMin = 1.0 / 255.0;                        // skip α < 1/255
constexpr double kTransmittanceMin = 1e-4;                       // stop before T would drop below 1e-4
constexpr double kSigmaExtent = 3.0;                             // screen footprint: at most 3σ
constexpr double kMaxPower = 0.5 * kSigmaExtent * kSigmaExtent;  // ½dᵀΣ⁻¹d at 3σ
constexpr int kTile = 16;                                        // 16×16 pixel tiles
constexpr double kFrustumClamp = 1.3;                            // EWA Jacobian evaluated inside 1.3× the frustum
constexpr double kPlaneDepthRange = 2.0;  // plane depth stays within [z/2, 2z] of the mean's depth z
constexpr double kSpanMargin = 1e-3;      // widens boxes and group tests so rounding never drops a pixel

// One pinhole camera in double precision: K = [[fx, skew, cx], [0, fy, cy], [0, 0, 1]], x_cam = R·x_world + t.
struct CameraParams {
  double fx = 1, fy = 1, cx = 0, cy = 0, skew = 0;
  double R[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};  // row-major
  double t[3] = {0, 0, 0};
  int64_t width = 0, height = 0;
  int64_t tiles_x() const { return (width + kTile - 1) / kTile; }
  int64_t tiles_y() const { return (height + kTile - 1) / kTile; }
};

// K [3,3] and T_cw [4,4] (any float dtype) as CameraParams. With `validate`, non-finite values,
// non-positive focal lengths and a K that is not [[fx, s, cx], [0, fy, cy], [0, 0, 1]] throw Error.
CameraParams camera_params(const torch::Tensor& K, const torch::Tensor& T_cw, int64_t width, int64_t height,
                           bool validate = false);

struct ProjectSettings {
  double near = 0.01;        // cull camera-space z < near
  double dilation = 0.3;     // px² added to the 2D covariance diagonal
  bool antialiased = false;  // scale opacity by sqrt(det Σ / det(Σ + dilation·I))
};

// Per-Gaussian screen-space record written by project_fwd, one row of `packed` [N, kRec].
// clang-format off
enum Rec : int {
  kU = 0, kV,           // mean in continuous pixel coordinates
  kConA, kConB, kConC,  // conic Σ'⁻¹ = [[A, B], [B, C]]
  kOpac,                // effective opacity o' (compensated in antialiased mode)
  kCut,                 // max power: min(4.5, ln(255·o')); beyond it the pixel is skipped
  kDepth,               // camera-space z of the mean
  kR, kG, kB,           // colour
  kNx, kNy, kNz,        // shortest axis in camera space, facing the camera
  kRx, kRy,             // half extents (px) of the cut ellipse's bounding box, slightly enlarged
  kRec = 16             // one 64-byte line in float
};
// clang-format on
constexpr int kGrad2d = 10;  // per-Gaussian 2D gradient: u, v, A, B, C, o', r, g, b, z

// ---- Projection (kernels_project.cpp) ----

struct Projection {
  torch::Tensor packed;  // [N, kRec] records (zeros when culled)
  torch::Tensor rects;   // [N, 4] int32 tile rectangle (x0, y0, x1, y1), half-open; empty when culled
  // Non-finite input values found on the way, per input: means, scales, quats, colors, opacities. Such
  // Gaussians are culled; the caller decides whether to fail (render() does).
  int64_t nonfinite[5] = {0, 0, 0, 0, 0};
};

// EWA projection of N Gaussians (all tensors contiguous, one floating dtype) into one camera.
Projection project_fwd(const torch::Tensor& means,      // [N, 3] world
                       const torch::Tensor& scales,     // [N, 3]
                       const torch::Tensor& quats,      // [N, 4] w, x, y, z (unnormalized)
                       const torch::Tensor& colors,     // [N, 3]
                       const torch::Tensor& opacities,  // [N]
                       const CameraParams& cam, const ProjectSettings& settings);

struct ProjectGrads {
  torch::Tensor means, scales, quats, opacities;  // shaped like the inputs
};

// Back-propagates the per-Gaussian 2D gradients through the projection (colours need no pass: they are
// grad2d[:, 6:9]). Recomputes the forward quantities from the inputs.
ProjectGrads project_bwd(const torch::Tensor& means, const torch::Tensor& scales, const torch::Tensor& quats,
                         const torch::Tensor& opacities, const CameraParams& cam, const ProjectSettings& settings,
                         const torch::Tensor& grad2d);  // [N, kGrad2d]

// ---- Tile binning and forward rasterization (kernels_fwd.cpp) ----

struct TileBins {
  torch::Tensor tile_offsets;  // [tiles + 1] int64: tile t owns isect_ids[offsets[t] : offsets[t+1]]
  torch::Tensor isect_ids;     // [I] int32 Gaussian ids, each tile's list sorted by (depth, id)
  int64_t intersections() const { return isect_ids.numel(); }
};

TileBins bin_tiles(const Projection& proj, const CameraParams& cam);

struct RasterOutput {
  torch::Tensor rgb, alpha, depth, normal;  // [3,H,W], [1,H,W], [1,H,W], [3,H,W]; [0] where RasterChannels leave out
  torch::Tensor final_T;                    // [H, W] transmittance after the last contributor
  torch::Tensor n_contrib;                  // [H, W] int32: 1 + tile-local index of the last contributor
  // [I] int32 per tile-list entry: the 8-pixel groups of its tile where it composited a pixel (bit r: row r's left
  // group, bit 16 + r: its right group). The AVX2 and AVX-512 float loops fill it when RasterChannels::group_hits
  // asks, and their backward visits exactly these groups; otherwise it is empty ([0]) and the backward finds the
  // groups itself.
  torch::Tensor group_hits;
};

// What the forward composites besides colour and alpha.
struct RasterChannels {
  bool normals = true;       // false skips the normal (a sixth of the pixel work); `normal` is then empty ([0])
  bool plane_depth = false;  // depth where the ray meets each Gaussian's plane instead of its mean's depth
  bool group_hits = false;   // record RasterOutput::group_hits for a backward to follow (inference needs none)
  bool depth = true;         // without normals, false skips the depth too; `depth` is then empty ([0])
};

RasterOutput rasterize_fwd(const torch::Tensor& packed, const TileBins& bins, const CameraParams& cam,
                           const double background[3], const RasterChannels& channels = {});

// Per pixel [1,H,W]: the depth of the first Gaussian after which the pixel's transmittance is 0.5 or less (the
// surface it shows; its mean or plane depth as in the forward), 0 where it never falls that far (alpha < 0.5).
torch::Tensor rasterize_median_depth(const torch::Tensor& packed, const TileBins& bins, const CameraParams& cam,
                                     bool plane_depth);

// Per Gaussian [N]: the largest weight w = α·T it reaches at any pixel (0 if culled or never composited).
torch::Tensor rasterize_max_weight(const torch::Tensor& packed, const TileBins& bins, const CameraParams& cam);

// ---- Backward rasterization (kernels_bwd.cpp) ----

// Per-Gaussian 2D gradients [N, kGrad2d] from the image gradients (undefined tensors count as zero; with both
// grad_alpha and grad_depth undefined, the pixel loops leave their terms out).
torch::Tensor rasterize_bwd(const torch::Tensor& packed, const TileBins& bins, const CameraParams& cam,
                            const double background[3], const torch::Tensor& final_T, const torch::Tensor& n_contrib,
                            const torch::Tensor& grad_rgb,          // [3, H, W]
                            const torch::Tensor& grad_alpha,        // [1, H, W]
                            const torch::Tensor& grad_depth,        // [1, H, W]
                            const torch::Tensor& group_hits = {});  // RasterOutput::group_hits, or undefined

// Instruction sets of the pixel loops and the projection (float only; double always runs portable). The
// kernels use the best the CPU has. All do the same IEEE operations in the same order, fusing the same multiply-adds
// (std::fma in the portable loops), so all give bit-identical images and gradients. avx512 runs two 8-pixel groups per
// register.
enum class Simd { portable = 0, avx2 = 1, avx512 = 2 };
const char* simd_name(Simd level);
Simd simd_supported();  // the best this CPU has: avx2 needs AVX2 + FMA, avx512 also AVX-512 F + DQ
Simd simd_level();      // the one in use
// Tests and benchmarks pick one; capped at simd_supported(). Returns the previous level.
Simd set_simd_level(Simd level);

}  // namespace isplat::splat
