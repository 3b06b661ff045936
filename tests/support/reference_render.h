// A dense per-pixel reference of the splatting forward model in plain torch ops (autograd gives its
// gradients), written independently of src/render and used only by the render tests.
#pragma once
#include "core/gaussians.h"
#include "geometry/camera_torch.h"
#include "render/render.h"

namespace isplat::test {

// Unbatched set and camera. Every pixel against every Gaussian (no tiles), with the same rules as the
// renderer: EWA with the 1.3× frustum clamp, dilation / antialiasing, 3σ cut, α = min(0.99, o·G),
// skip α < 1/255, stop before T < 1e-4, depth order (stable by index). Mean depth only (options.depth is
// ignored); median_depth when maps.median_depth asks (maps' other flags are ignored: every map is made).
RenderOutput reference_render(const Gaussians& gaussians, const Camera& camera, const RenderOptions& options,
                              const RenderMaps& maps = {});

}  // namespace isplat::test
