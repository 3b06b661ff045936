// One scored pair broken down by image region and scored again in its source view (scoring.regions).
#pragma once
#include <torch/types.h>

#include "data/tuples.h"
#include "eval/methods.h"
#include "eval/report.h"
#include "metrics/metrics.h"
#include "render/render.h"

namespace isplat {

// Fills r.regions ("all" for the whole mask, then metrics/regions image_regions of the target) and, for methods
// that render Gaussians, r.source_view (the scene rendered from the source camera against the source photo, on the
// pixels with source depth, or every pixel when it has none). ref_depth: the target's reference depth (0 where invalid)
// or undefined; lpips: the variant regions use, or nullptr (LPIPS NaN).
void score_regions(const MethodOutput& output, const ViewTensors& source, const ViewTensors& target,
                   const torch::Tensor& mask, const torch::Tensor& ref_depth, const Lpips* lpips,
                   const RenderOptions& render_options, PairResult& r);

}  // namespace isplat
