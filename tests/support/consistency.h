// Multi-view depth consistency: back-project one frame's depth, project into another, compare depths.
// Agreement checks poses, intrinsics and depth conventions of a reader end to end.
#pragma once
#include "data/sequence.h"

namespace isplat::test {

struct Consistency {
  int64_t checked = 0;    // source samples landing inside the target with valid target depth
  double agree = 0;       // fraction of those within `tolerance` relative depth error
  double median_rel = 1;  // median relative depth error over checked samples
};

Consistency depth_consistency(const LoadedFrame& source, const LoadedFrame& target, double tolerance = 0.02,
                              int step = 3);

}  // namespace isplat::test
