// k nearest neighbours of 2D points (supports in image space) with a uniform grid hash: O(N k), not O(N^2).
#pragma once
#include <torch/types.h>

namespace isplat {

// points [N,2] float. Returns indices [N,k] (int64) of each point's k nearest other points, nearest
// first, ties by index; when N <= k, the missing entries repeat the point's own index.
torch::Tensor knn_2d(const torch::Tensor& points, int64_t k);

}  // namespace isplat
