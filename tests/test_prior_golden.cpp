// Golden depth priors: the dataset and sparse priors, the prompt alignment and the floor-scale fit give the values
// they gave before depth_prior.cpp was split into one file per prior (FNV-1a 64 of the tensors' bytes).
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <torch/torch.h>

#include "geometry/camera_torch.h"
#include "prior/depth_prior.h"
#include "support/test_util.h"

using namespace isplat;

// Taken with ISPLAT_PRINT_GOLDEN=1 at commit 1752bc8 (prior code as at e8a194c but for the weights lookup) on an Intel
// Xeon (ATen CPU capability AVX512). The alignment ends in LibTorch's vectorized exp and bilinear resize, whose last
// bits can follow the CPU capability, so the tensor hashes are checked only under the capability they were taken with;
// elsewhere the means are checked to 1e-5. The floor fit is scalar C++ and Eigen, and the prompts are drawn by
// std::mt19937_64: exact everywhere.

namespace prior_golden {
using test::aten_capability;
using test::fnv1a;

constexpr int64_t kPriorGoldenH = 40, kPriorGoldenW = 56;

// A camera 1.6 m above a floor facing a wall 5 m away, with a box on the floor; planar depth.
torch::Tensor room_depth() {
  auto d = torch::empty({kPriorGoldenH, kPriorGoldenW});
  auto a = d.accessor<float, 2>();
  const double fy = 40.0, cy = 20.0;
  for (int64_t i = 0; i < kPriorGoldenH; ++i)
    for (int64_t j = 0; j < kPriorGoldenW; ++j) {
      double z = 5.0;
      const double y = (static_cast<double>(i) + 0.5 - cy) / fy;
      if (y > 0) z = std::min(z, 1.6 / y);
      if (i > 24 && j > 10 && j < 22) z = std::min(z, 2.5);
      a[i][j] = static_cast<float>(z);
    }
  return d;
}

torch::Tensor room_K() {
  return make_K(40.0, 40.0, 28.0, 20.0);
}

torch::Tensor room_image() {
  auto im = torch::empty({3, kPriorGoldenH, kPriorGoldenW});
  auto a = im.accessor<float, 3>();
  for (int64_t c = 0; c < 3; ++c)
    for (int64_t i = 0; i < kPriorGoldenH; ++i)
      for (int64_t j = 0; j < kPriorGoldenW; ++j)
        a[c][i][j] = static_cast<float>(0.5 + 0.4 * std::sin(0.2 * static_cast<double>(i * (c + 1) + j)));
  return im;
}

constexpr uint64_t kPrompts = 0x2541ca15812ecce4ull, kDatasetDepth = 0xc53599e2a3f2884aull,
                   kDatasetValid = 0xb10d631e02c2a73aull, kAligned = 0x2b6a1db60925baa7ull,
                   kPlain = 0x61e9f91ae1577fa5ull, kSparse = 0xcfd5b5c5309f3748ull,
                   kSparseValid = 0x44b28ea9ccc62183ull;
constexpr int64_t kLevels = 1;
constexpr double kFloor = 2.4408301370512273, kAlignedMean = 4.6670279502868652, kPlainMean = 4.664738655090332,
                 kSparseMean = 4.6768579483032227;

// The test cases live in the namespace too: a using-directive would leak its names into the next file of a
// unity batch.

TEST_CASE("prior golden: the priors, the alignment and the floor fit are those taken before the split",
          "[prior][golden]") {
  const bool print = std::getenv("ISPLAT_PRINT_GOLDEN") != nullptr;
  const bool same_capability = aten_capability() == "avx512";
  const torch::Tensor depth = room_depth(), K = room_K(), image = room_image();
  auto valid = torch::ones({kPriorGoldenH, kPriorGoldenW});
  valid[3][4] = 0.0f;

  const torch::Tensor prompts = draw_prompts(depth, valid, 300, 0.02, 7);
  SparsePriorOptions smooth;
  const torch::Tensor mono = depth.pow(0.8) * 0.5;
  int64_t levels = 0;
  const torch::Tensor aligned = align_to_prompts(mono, prompts, smooth, &levels);
  SparsePriorOptions plain = smooth;
  plain.depth_range = 0.0;
  plain.cross_validate = false;
  const torch::Tensor aligned_plain = align_to_prompts(mono, prompts, plain);

  PriorOptions o;
  o.type = "sparse";
  o.sparse.mono = "none";
  o.sparse.densify = "fit";  // the alignment the golden values were taken with (the default blends since 2026-12-06)
  o.sparse.prompts = 200;
  PriorInput in;
  in.image = image, in.K = K, in.depth = depth, in.valid = valid, in.seed = 3;
  const PriorOutput sparse = make_depth_prior(o)->predict(in);
  o.type = "dataset";
  const PriorOutput dataset = make_depth_prior(o)->predict(in);

  const double floor = floor_height_scale(depth * 0.4f, valid, K, 1.6);
  if (print) {
    std::printf("prompts 0x%016llxull\naligned 0x%016llxull %.17g levels %lld\nplain 0x%016llxull %.17g\n",
                (unsigned long long)fnv1a(prompts), (unsigned long long)fnv1a(aligned), aligned.mean().item<double>(),
                (long long)levels, (unsigned long long)fnv1a(aligned_plain), aligned_plain.mean().item<double>());
    std::printf("sparse 0x%016llxull %.17g valid 0x%016llxull\ndataset 0x%016llxull 0x%016llxull\nfloor %.17g\n",
                (unsigned long long)fnv1a(sparse.depth), sparse.depth.mean().item<double>(),
                (unsigned long long)fnv1a(sparse.valid), (unsigned long long)fnv1a(dataset.depth),
                (unsigned long long)fnv1a(dataset.valid), floor);
    return;
  }
  CHECK(fnv1a(prompts) == kPrompts);
  CHECK(levels == kLevels);
  CHECK(fnv1a(dataset.depth) == kDatasetDepth);
  CHECK(fnv1a(dataset.valid) == kDatasetValid);
  CHECK(floor == kFloor);
  CHECK(aligned.mean().item<double>() == Approx(kAlignedMean).epsilon(1e-5));
  CHECK(aligned_plain.mean().item<double>() == Approx(kPlainMean).epsilon(1e-5));
  CHECK(sparse.depth.mean().item<double>() == Approx(kSparseMean).epsilon(1e-5));
  if (same_capability) {
    CHECK(fnv1a(aligned) == kAligned);
    CHECK(fnv1a(aligned_plain) == kPlain);
    CHECK(fnv1a(sparse.depth) == kSparse);
    CHECK(fnv1a(sparse.valid) == kSparseValid);
  }
}

}  // namespace prior_golden
