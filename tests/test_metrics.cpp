// Metrics: PSNR and SSIM against hand-computed values and an independent reference SSIM, and LPIPS-squeeze
// against the properties it must have (zero on identical images, symmetric, monotone in blur and noise);
// the stability measures (holes, cracks, normal incoherence) on hand-built renders.
#include <catch2/catch.hpp>

#include <torch/torch.h>

#include <cmath>

#include "core/error.h"
#include "geometry/camera_torch.h"
#include "metrics/metrics.h"
#include "metrics/stability.h"
#include "support/test_util.h"

using namespace isplat;

namespace {
// Straightforward SSIM: a 2D Gaussian window at every valid pixel, no separability, double precision.
double reference_ssim(const torch::Tensor& a, const torch::Tensor& b) {
  const int R = 5;
  double w[11][11], sum = 0;
  for (int y = -R; y <= R; ++y)
    for (int x = -R; x <= R; ++x) sum += w[y + R][x + R] = std::exp(-(x * x + y * y) / (2 * 1.5 * 1.5));
  const int64_t C = a.size(0), H = a.size(1), W = a.size(2);
  auto A = a.to(torch::kFloat64).contiguous(), B = b.to(torch::kFloat64).contiguous();
  const double *pa = A.data_ptr<double>(), *pb = B.data_ptr<double>();
  double total = 0;
  int64_t n = 0;
  for (int64_t i = R; i < H - R; ++i)
    for (int64_t j = R; j < W - R; ++j) {
      double s = 0;
      for (int64_t c = 0; c < C; ++c) {
        double mx = 0, my = 0, xx = 0, yy = 0, xy = 0;
        for (int y = -R; y <= R; ++y)
          for (int x = -R; x <= R; ++x) {
            const double wt = w[y + R][x + R] / sum, u = pa[(c * H + i + y) * W + j + x],
                         v = pb[(c * H + i + y) * W + j + x];
            mx += wt * u, my += wt * v, xx += wt * u * u, yy += wt * v * v, xy += wt * u * v;
          }
        const double C1 = 1e-4, C2 = 9e-4;
        s += ((2 * mx * my + C1) * (2 * (xy - mx * my) + C2)) /
             ((mx * mx + my * my + C1) * (xx - mx * mx + yy - my * my + C2));
      }
      total += s / C;
      ++n;
    }
  return total / n;
}

torch::Tensor test_image(int64_t H, int64_t W) {
  auto y = torch::linspace(0, 1, H).view({1, H, 1}), x = torch::linspace(0, 1, W).view({1, 1, W});
  auto c = torch::tensor({1.0f, 0.6f, 0.3f}).view({3, 1, 1});
  return (0.5 + 0.4 * torch::sin(9 * x * c + 5 * y) * torch::cos(7 * y * c)).expand({3, H, W}).contiguous();
}

torch::Tensor blur(const torch::Tensor& img, int r) {
  namespace F = torch::nn::functional;
  auto k = torch::ones({3, 1, 2 * r + 1, 2 * r + 1}) / ((2 * r + 1) * (2 * r + 1));
  return F::conv2d(F::pad(img.unsqueeze(0), F::PadFuncOptions({r, r, r, r}).mode(torch::kReplicate)), k,
                   F::Conv2dFuncOptions().groups(3))[0];
}
}  // namespace

TEST_CASE("metrics: PSNR, masked and not, against hand-computed values", "[metrics]") {
  auto a = torch::full({3, 8, 8}, 0.5f), b = torch::full({3, 8, 8}, 0.6f);
  CHECK(psnr(a, b) == Approx(20.0).epsilon(1e-6));
  CHECK(std::isinf(psnr(a, a)));
  b.narrow(2, 4, 4).fill_(0.5f + 0.01f);  // right half: error 0.01
  auto left = torch::zeros({8, 8});
  left.narrow(1, 0, 4).fill_(1);
  CHECK(psnr(a, b, left) == Approx(20.0).epsilon(1e-6));
  CHECK(psnr(a, b, 1 - left) == Approx(40.0).epsilon(1e-4));
  CHECK(psnr(a, b) == Approx(-10 * std::log10(0.5 * (0.01 + 1e-4))).epsilon(1e-6));
  CHECK(std::isnan(psnr(a, b, torch::zeros({8, 8}))));
}

TEST_CASE("metrics: SSIM matches a reference implementation to 1e-4", "[metrics]") {
  torch::manual_seed(1);
  auto a = test_image(40, 52);
  for (double noise : {0.02, 0.1, 0.3}) {
    auto b = (a + noise * torch::randn_like(a)).clamp(0, 1);
    const double ours = ssim(a, b), ref = reference_ssim(a, b);
    INFO("noise " << noise << " ours " << ours << " reference " << ref);
    CHECK(std::abs(ours - ref) < 1e-4);
  }
  CHECK(ssim(a, a) == Approx(1.0));
  CHECK(ssim(a, blur(a, 2)) < ssim(a, blur(a, 1)));
  // Masked: only the left half's window centres count.
  auto b = a.clone();
  b.narrow(2, 26, 26).copy_((a.narrow(2, 26, 26) + 0.3 * torch::randn({3, 40, 26})).clamp(0, 1));
  auto left = torch::zeros({40, 52});
  left.narrow(1, 0, 20).fill_(1);
  CHECK(ssim(a, b, left) == Approx(1.0));
  CHECK(ssim(a, b) < 0.9);
}

TEST_CASE("metrics: LPIPS-squeeze is zero on identical images, symmetric and monotone", "[metrics][lpips]") {
  ISPLAT_REQUIRE_WEIGHTS();
  std::string why;
  auto lp = Lpips::from_folder("squeeze", test::project_weights_dir(), why);
  REQUIRE(lp != nullptr);  // the heads and backbone ship in weights/
  torch::manual_seed(4);
  auto a = test_image(64, 64);
  CHECK((*lp)(a, a) == Approx(0.0).margin(1e-9));
  auto n1 = (a + 0.05 * torch::randn_like(a)).clamp(0, 1), n2 = (a + 0.15 * torch::randn_like(a)).clamp(0, 1),
       n3 = (a + 0.3 * torch::randn_like(a)).clamp(0, 1);
  const double l1 = (*lp)(a, n1), l2 = (*lp)(a, n2), l3 = (*lp)(a, n3);
  CHECK(l1 > 0);
  CHECK(l1 < l2);
  CHECK(l2 < l3);
  CHECK((*lp)(n2, a) == Approx(l2).epsilon(1e-5));
  const double b1 = (*lp)(a, blur(a, 1)), b2 = (*lp)(a, blur(a, 2)), b3 = (*lp)(a, blur(a, 4));
  CHECK(b1 < b2);
  CHECK(b2 < b3);
  // One network pass, many masks: the two-step form gives exactly the one-call scores, masked or not.
  const auto maps = lp->distance_maps(a, n2);
  auto left = torch::zeros({64, 64});
  left.narrow(1, 0, 32).fill_(1);
  CHECK(Lpips::mean_distance(maps) == (*lp)(a, n2));
  CHECK(Lpips::mean_distance(maps, left) == (*lp)(a, n2, left));
  CHECK(std::isnan(Lpips::mean_distance(maps, torch::zeros({64, 64}))));
  std::string why2;
  CHECK(Lpips::from_folder("alex", test::project_weights_dir(), why2) == nullptr);  // no AlexNet backbone here
  CHECK_THAT(why2, Catch::Contains("alexnet_features.safetensors"));
}

TEST_CASE("stability: hole and crack rates on hand-built renders", "[metrics]") {
  const int64_t H = 10, W = 10;
  auto mask = torch::ones({H, W});
  auto alpha = torch::ones({1, H, W});
  alpha.narrow(1, 0, 5).narrow(2, 0, 5).fill_(0.2);  // a 5x5 hole: a quarter of the frame
  CHECK(hole_rate(alpha, mask) == Approx(0.25));
  mask.narrow(0, 5, 5).zero_();  // only the top half counts: 25 of 50 pixels
  CHECK(hole_rate(alpha, mask) == Approx(0.5));
  CHECK(std::isnan(hole_rate(alpha, torch::zeros({H, W}))));
  CHECK_THROWS_AS(hole_rate(torch::ones({3, H, W}), torch::ones({H, W})), Error);

  // A smooth reference plane at 2 m; the render tears along the column boundary 4|5 (z jumps to 3 m).
  const auto full = torch::ones({H, W}), opaque = torch::ones({1, H, W});
  const auto ref = torch::full({H, W}, 2.0);
  auto depth = torch::full({1, H, W}, 2.0);
  depth.narrow(2, 5, 5).fill_(3.0);
  CHECK(crack_rate(depth, opaque, ref, full) == Approx(10.0 / 180.0));  // 10 torn of 90 + 90 neighbour pairs
  // depth is the alpha-weighted sum: half-transparent pixels with half the sum are the same depth.
  CHECK(crack_rate(depth * 0.6, opaque * 0.6, ref, full) == Approx(10.0 / 180.0));
  // Where the reference has the same edge, the jump is geometry, not a crack.
  auto ref_edge = ref.clone();
  ref_edge.narrow(1, 5, 5).fill_(3.0);
  CHECK(crack_rate(depth, opaque, ref_edge, full) == 0.0);
  // Holes are not cracks.
  CHECK(std::isnan(crack_rate(depth, torch::zeros({1, H, W}), ref, full)));

  // A silhouette drawn one pixel off: the reference steps at 4|5, the render at 5|6. Without a margin the
  // misplaced step is a crack on every row; with edge_margin 2 the pairs near the reference edge are skipped,
  // and a tear in the middle of a surface, far from that edge, still counts.
  auto shifted = torch::full({1, H, W}, 2.0);
  shifted.narrow(2, 6, 4).fill_(3.0);
  CHECK(crack_rate(shifted, opaque, ref_edge, full) == Approx(10.0 / 170.0));  // 10 of 80 + 90 smooth pairs
  StabilityOptions margin;
  margin.edge_margin = 2;
  CHECK(crack_rate(shifted, opaque, ref_edge, full, margin) == 0.0);
  auto torn = shifted.clone();
  torn.narrow(1, 0, 1).narrow(2, 0, 2).fill_(2.5);  // row 0, columns 0..1: left of the band (columns 2..7)
  // Counted pairs: columns 0..1 and 8..9 only (0|1 and 8|9 on 10 rows, 9 down pairs in 4 columns: 20 + 36 = 56); the
  // tear breaks the two down pairs below it.
  CHECK(crack_rate(torn, opaque, ref_edge, full, margin) == Approx(2.0 / 56.0));
  CHECK_THROWS_AS(crack_rate(shifted, opaque, ref_edge, torch::ones({H, W + 1}), margin), Error);

  // With holes_break, a hole in the smooth plane counts as broken pairs instead of dropping out of the measure:
  // a 2x2 hole at rows 0..1, columns 0..1 of an intact render (the 4 pairs inside it and the 4 that leave it).
  auto holed = opaque.clone();
  holed.narrow(1, 0, 2).narrow(2, 0, 2).fill_(0.0);
  const auto flat = torch::full({1, H, W}, 2.0);
  CHECK(crack_rate(flat, holed, ref, full) == 0.0);  // the default measure skips the hole's pairs
  StabilityOptions holes;
  holes.holes_break = true;
  CHECK(crack_rate(flat, holed, ref, full, holes) == Approx(8.0 / 180.0));
  CHECK(std::isnan(crack_rate(flat, torch::zeros({1, H, W}), ref, torch::zeros({H, W}), holes)));
  CHECK(crack_rate(flat, torch::zeros({1, H, W}), ref, full, holes) == 1.0);  // all empty: every pair broken

  // crack_side splits the broken pairs by where the deviant pixel errs. On the 2 m plane, column 2 is drawn
  // nearer (1.5 m: a fringe) and column 7 farther (3 m: seen through): 2 x 10 broken pairs each side.
  auto sided = torch::full({1, H, W}, 2.0);
  sided.narrow(2, 2, 1).fill_(1.5);
  sided.narrow(2, 7, 1).fill_(3.0);
  StabilityOptions nearer, farther;
  nearer.crack_side = CrackSide::nearer;
  farther.crack_side = CrackSide::farther;
  CHECK(crack_rate(sided, opaque, ref, full) == Approx(40.0 / 180.0));
  CHECK(crack_rate(sided, opaque, ref, full, nearer) == Approx(20.0 / 180.0));
  CHECK(crack_rate(sided, opaque, ref, full, farther) == Approx(20.0 / 180.0));
  // The deviant pixel decides, not which of the two renders nearer: on a reference ramp 2 | 2.01, a render 2 | 2.2
  // errs farther at the second pixel, though the first is the nearer of the two.
  const auto ramp_ref = torch::tensor({2.0, 2.01}).reshape({1, 2}), pair_mask = torch::ones({1, 2});
  const auto ramp = torch::tensor({2.0, 2.2}).reshape({1, 1, 2}), ramp_alpha = torch::ones({1, 1, 2});
  CHECK(crack_rate(ramp, ramp_alpha, ramp_ref, pair_mask, farther) == 1.0);
  CHECK(crack_rate(ramp, ramp_alpha, ramp_ref, pair_mask, nearer) == 0.0);
  // With holes_break a hole errs farther: nothing is drawn there.
  StabilityOptions holes_nearer = nearer, holes_farther = farther;
  holes_nearer.holes_break = holes_farther.holes_break = true;
  CHECK(crack_rate(flat, holed, ref, full, holes_nearer) == 0.0);
  CHECK(crack_rate(flat, holed, ref, full, holes_farther) == Approx(8.0 / 180.0));
  // min_error keeps the breaks whose deviant pixel errs by at least that share: column 7 errs by +50%, column 2 by
  // −25%, so 0.3 keeps only column 7's 20 pairs and 0.6 none; a hole (holes_break) always counts.
  StabilityOptions big = {};
  big.min_error = 0.3;
  CHECK(crack_rate(sided, opaque, ref, full, big) == Approx(20.0 / 180.0));
  big.min_error = 0.6;
  CHECK(crack_rate(sided, opaque, ref, full, big) == 0.0);
  big.holes_break = true;
  CHECK(crack_rate(flat, holed, ref, full, big) == Approx(8.0 / 180.0));
  // edge_side: where the deviant pixel lies in the reference. The reference steps 2 | 3 m at columns 4 | 5. Drawn
  // one column too wide (column 5 at 2 m), the deviant pixel is on the edge's far side; one column too narrow (column
  // 4 at 3 m), on its near side. Each breaks 10 of the 170 smooth pairs.
  auto narrow = torch::full({1, H, W}, 2.0);
  narrow.narrow(2, 4, 6).fill_(3.0);
  StabilityOptions near_side, far_side;
  near_side.edge_side = EdgeSide::near;
  far_side.edge_side = EdgeSide::far;
  CHECK(crack_rate(shifted, opaque, ref_edge, full, far_side) == Approx(10.0 / 170.0));
  CHECK(crack_rate(shifted, opaque, ref_edge, full, near_side) == 0.0);
  CHECK(crack_rate(narrow, opaque, ref_edge, full, near_side) == Approx(10.0 / 170.0));
  CHECK(crack_rate(narrow, opaque, ref_edge, full, far_side) == 0.0);
  CHECK(crack_rate(sided, opaque, ref, full, far_side) == 0.0);  // no reference edge anywhere: neither side
  CHECK(parse_edge_side("far") == EdgeSide::far);
  CHECK_THROWS_WITH(parse_edge_side("behind"), Catch::Contains("'behind'"));
  CHECK(parse_crack_side("nearer") == CrackSide::nearer);
  CHECK_THROWS_WITH(parse_crack_side("front"), Catch::Contains("'front'"));

  // The crack map puts those breaks where they are: the deviant columns 2 (blue: nearer) and 7 (red: farther), grey
  // on every other scored pixel, black outside the mask; crack_side keeps one side.
  auto half = full.clone();
  half.narrow(0, 5, 5).zero_();  // only the top 5 rows are scored
  const auto map = crack_map(sided, opaque, ref, half);
  REQUIRE(map.sizes() == torch::IntArrayRef({3, H, W}));
  const auto red = (map[0] == 1.0f) & (map[2] < 0.5f), blue = (map[2] == 1.0f) & (map[0] < 0.5f);
  const auto grey = (map[0] == map[1]) & (map[1] == map[2]) & (map[0] > 0);
  CHECK(red.narrow(0, 0, 5).select(1, 7).all().item<bool>());
  CHECK(blue.narrow(0, 0, 5).select(1, 2).all().item<bool>());
  CHECK(red.sum().item<int64_t>() == 5);
  CHECK(blue.sum().item<int64_t>() == 5);
  CHECK(grey.sum().item<int64_t>() == 40);
  CHECK((map.narrow(1, 5, 5) == 0).all().item<bool>());
  const auto far_only = crack_map(sided, opaque, ref, half, farther);
  CHECK(((far_only[2] == 1.0f) & (far_only[0] < 0.5f)).sum().item<int64_t>() == 0);
  CHECK(((far_only[0] == 1.0f) & (far_only[2] < 0.5f)).sum().item<int64_t>() == 5);
  CHECK((crack_map(flat, opaque, ref, full).max() < 0.5f).item<bool>());  // an intact render: grey only
  CHECK_THROWS_AS(crack_map(sided, opaque, ref, torch::ones({H, W + 1})), Error);
}

TEST_CASE("stability: normal incoherence is 0 on a coherent plane and the tilt on a checkerboard", "[metrics]") {
  const int64_t H = 12, W = 16;
  const auto K = make_K(20.0, 20.0, W / 2.0, H / 2.0);
  const auto ref = torch::full({H, W}, 3.0);  // fronto-parallel: planar everywhere
  const auto mask = torch::ones({H, W}), alpha = torch::ones({1, H, W});
  auto n = torch::zeros({3, H, W});
  n[2].fill_(-1.0);
  CHECK(normal_incoherence_deg(n * 0.7, alpha, ref, K, mask) == Approx(0.0).margin(1e-6));
  // Every other pixel tilted by 10 degrees about x: each neighbour pair differs by exactly 10.
  const double t = 10.0 * M_PI / 180.0;
  for (int64_t i = 0; i < H; ++i)
    for (int64_t j = 0; j < W; ++j)
      if ((i + j) % 2) n[1][i][j] = -std::sin(t), n[2][i][j] = -std::cos(t);
  CHECK(normal_incoherence_deg(n, alpha, ref, K, mask) == Approx(10.0).epsilon(1e-6));
  // A reference without valid depth leaves nothing to measure.
  CHECK(std::isnan(normal_incoherence_deg(n, alpha, torch::zeros({H, W}), K, mask)));
}
