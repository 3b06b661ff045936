// Geometry-guided sampler: density follows 3D area, discontinuities and holes get no supports (unless fill_px
// fills the holes), the count equals the budget, seeds are reproducible, and adaptive budgets scale with the scene.
#include <catch2/catch.hpp>

#include <tuple>

#include <torch/torch.h>

#include "core/config.h"
#include "core/error.h"
#include "geometry/camera_torch.h"
#include "sampler/base_gaussians.h"
#include "sampler/depth_fill.h"
#include "sampler/sampler.h"

using namespace isplat;

namespace {
// 48 x 64 quads, so 8x8 blocks and 4 column strips align with whole quads.
constexpr int64_t kH = 49, kW = 65;
const double fx = 60.0, fy = 60.0, cx = 32.0, cy = 24.0;
torch::Tensor K() {
  return make_K(fx, fy, cx, cy);
}
torch::Tensor image() {
  return torch::rand({3, kH, kW});
}
torch::Tensor ones() {
  return torch::ones({kH, kW});
}
SamplerOptions fixed(int64_t n) {
  SamplerOptions o;
  o.budget = n;
  return o;
}
// [N] bool: which supports sit on a pixel centre (both coordinates at +0.5), as pixel and edge supports do.
torch::Tensor on_pixel_centre(const torch::Tensor& uv) {
  return ((uv - 0.5 - (uv - 0.5).floor()).abs().lt(1e-6)).all(1);
}
// Counts of supports whose u falls in each of `bins` vertical strips.
std::vector<double> column_histogram(const Supports& s, int bins) {
  std::vector<double> h(bins, 0.0);
  auto u = s.uv.select(1, 0);
  for (int64_t k = 0; k < s.count(); ++k) {
    const double x = (u[k].item<double>() - 0.5) / (kW - 1);
    h[std::min(bins - 1, static_cast<int>(x * bins))] += 1;
  }
  return h;
}
}  // namespace

TEST_CASE("sampler: a fronto-parallel plane gets a uniform density and the exact count", "[sampler]") {
  auto depth = torch::full({kH, kW}, 2.0f);
  const Supports s = sample_supports(depth, ones(), K(), image(), fixed(6000), 1);
  REQUIRE(s.count() == 6000);
  // Stratified allocation runs over quads in row-major order: each quad row (a contiguous stretch)
  // gets its share N/48 +- 1, and each 8x6-quad block, made of 6 row stretches, N/64 +- 6.
  std::vector<int> rows(kH - 1, 0), blocks(8 * 8, 0);
  auto uv = s.uv.contiguous();
  const float* p = uv.data_ptr<float>();
  for (int64_t k = 0; k < s.count(); ++k) {
    const int row = std::min<int>(kH - 2, static_cast<int>(p[2 * k + 1] - 0.5));
    rows[row]++;
    blocks[(row / 6) * 8 + std::min(7, static_cast<int>((p[2 * k] - 0.5) / 8))]++;
  }
  for (int c : rows) CHECK(std::abs(c - 6000.0 / 48) <= 1.0);
  for (int c : blocks) CHECK(std::abs(c - 6000.0 / 64) <= 6.0);
  // Represented areas add up to the plane's area between pixel centres.
  const double area = ((kW - 1) * 2.0 / fx) * ((kH - 1) * 2.0 / fy);
  CHECK(s.area.sum().item<double>() == Approx(area).epsilon(1e-4));
  CHECK(torch::allclose(s.depth, torch::full({6000}, 2.0f)));
}

TEST_CASE("sampler: a slanted plane gets density proportional to its 3D area", "[sampler]") {
  // Plane z = 1 + 0.9 * X, i.e. depth rising to the right: columns far away cover more surface.
  auto u = torch::arange(kW, torch::kFloat32) + 0.5;
  auto x = (u - cx) / fx;
  auto z_row = 1.0 / (1.0 - 0.9 * x);  // z = 1 + 0.9 * x * z
  auto depth = z_row.unsqueeze(0).expand({kH, kW}).contiguous();
  const Supports s = sample_supports(depth, ones(), K(), image(), fixed(20000), 3);
  // Expected share of each strip from the areas of its triangles, computed independently.
  auto P = backproject_depth(depth, K());
  std::vector<double> area(4, 0.0);
  for (int64_t j = 0; j + 1 < kW; ++j) {
    double col = 0;
    for (int64_t i = 0; i + 1 < kH; ++i) {
      auto a = P[i][j], b = P[i][j + 1], c = P[i + 1][j], d = P[i + 1][j + 1];
      col += 0.5 * torch::cross(b - a, c - a).norm().item<double>() +
             0.5 * torch::cross(d - b, c - b).norm().item<double>();
    }
    area[std::min<int64_t>(3, j * 4 / (kW - 1))] += col;
  }
  const double total = area[0] + area[1] + area[2] + area[3];
  const auto h = column_histogram(s, 4);
  for (int b = 0; b < 4; ++b) CHECK(h[b] / 20000.0 == Approx(area[b] / total).margin(0.005));
  CHECK(h[3] > 1.5 * h[0]);  // really non-uniform in the image
}

TEST_CASE("sampler: image_share moves supports toward an even spread per pixel and keeps the total area", "[sampler]") {
  // The slanted plane of the test above: far columns cover more area.
  auto u = torch::arange(kW, torch::kFloat32) + 0.5;
  auto z_row = 1.0 / (1.0 - 0.9 * (u - cx) / fx);
  auto depth = z_row.unsqueeze(0).expand({kH, kW}).contiguous();
  SamplerOptions area_only = fixed(20000), half = fixed(20000), even = fixed(20000);
  half.image_share = 0.5;
  even.image_share = 1.0;
  const Supports a = sample_supports(depth, ones(), K(), image(), area_only, 3);
  const Supports m = sample_supports(depth, ones(), K(), image(), half, 3);
  const Supports e = sample_supports(depth, ones(), K(), image(), even, 3);
  REQUIRE(m.count() == 20000);
  REQUIRE(e.count() == 20000);
  const auto ha = column_histogram(a, 4), hm = column_histogram(m, 4), he = column_histogram(e, 4);
  // Fully even: every strip gets its share of the image (16 of the 64 quad columns each).
  for (int b = 0; b < 4; ++b) CHECK(he[b] / 20000.0 == Approx(0.25).margin(0.005));
  // Half and half: the mean of the two allocations.
  for (int b = 0; b < 4; ++b) CHECK(hm[b] == Approx(0.5 * (ha[b] + he[b])).margin(0.005 * 20000));
  // Each support's share of area follows its density, so the areas still add up to the surface.
  const double total = a.area.sum().item<double>();
  CHECK(m.area.sum().item<double>() == Approx(total).epsilon(1e-3));
  CHECK(e.area.sum().item<double>() == Approx(total).epsilon(1e-3));
  // Near supports stand for less area than far ones once spread evenly per pixel.
  auto near = e.uv.select(1, 0)<16, far = e.uv.select(1, 0)> 48;
  CHECK(e.area.masked_select(near).mean().item<double>() < 0.5 * e.area.masked_select(far).mean().item<double>());
}

TEST_CASE("sampler: pixel_floor lifts the sparse (near) strips to an even share and leaves denser ones by area",
          "[sampler]") {
  auto u = torch::arange(kW, torch::kFloat32) + 0.5;
  auto z_row = 1.0 / (1.0 - 0.9 * (u - cx) / fx);  // the slanted plane above: far columns cover more area
  auto depth = z_row.unsqueeze(0).expand({kH, kW}).contiguous();
  SamplerOptions area_only = fixed(20000), floored = fixed(20000);
  floored.pixel_floor = 1.0;
  const Supports a = sample_supports(depth, ones(), K(), image(), area_only, 3);
  const Supports f = sample_supports(depth, ones(), K(), image(), floored, 3);
  REQUIRE(f.count() == 20000);
  const auto ha = column_histogram(a, 4), hf = column_histogram(f, 4);
  REQUIRE(ha[0] < 0.25 * 20000);  // by area alone the near strip gets less than its share of the image ...
  CHECK(hf[0] > ha[0]);           // ... the floor lifts it ...
  CHECK(hf[3] < ha[3]);           // ... from the far strip, which still gets the most
  CHECK(hf[3] > hf[0]);
  // Near triangles draw exactly the even share (a quarter of the unfloored total per strip) and far ones their
  // area, so near / far = (total / 4) / far area = 0.25 n / (far count by area alone).
  CHECK(hf[0] / hf[3] == Approx(0.25 * 20000 / ha[3]).epsilon(0.05));
  CHECK(f.area.sum().item<double>() == Approx(a.area.sum().item<double>()).epsilon(1e-3));
  // A floor at or below what image_share already gives changes nothing.
  SamplerOptions half = fixed(20000), half_floor = fixed(20000);
  half.image_share = half_floor.image_share = 0.5;
  half_floor.pixel_floor = 0.5;
  CHECK(torch::equal(sample_supports(depth, ones(), K(), image(), half, 3).uv,
                     sample_supports(depth, ones(), K(), image(), half_floor, 3).uv));
}

TEST_CASE("sampler: edge_supports covers the pixels on both sides of a depth step and the border", "[sampler]") {
  // Columns 0..31 at 2 m, 32..64 at 6 m: the quads between columns 31 and 32 are rejected.
  auto depth = torch::full({kH, kW}, 6.0f);
  depth.narrow(1, 0, 32).fill_(2.0f);
  SamplerOptions o = fixed(4000);
  const Supports faces = sample_supports(depth, ones(), K(), image(), o, 2);
  o.edge_supports = true;
  const Supports s = sample_supports(depth, ones(), K(), image(), o, 2);
  REQUIRE(s.count() == 4000);
  // Every row has a support at the centres of columns 31 and 32, and at both ends of the image.
  auto centre = [&](double u, double v) {
    return ((s.uv.select(1, 0) - u).abs().lt(1e-4) & (s.uv.select(1, 1) - v).abs().lt(1e-4)).any().item<bool>();
  };
  int64_t missing = 0;
  for (int64_t i = 0; i < kH; ++i)
    for (double u : {0.5, 31.5, 32.5, kW - 0.5}) missing += !centre(u, i + 0.5);
  CHECK(missing == 0);
  // Edge pixels: 4 per row, plus the rest of the top and bottom rows.
  const int64_t edges = 4 * kH + 2 * (kW - 4);
  CHECK(on_pixel_centre(s.uv).sum().item<int64_t>() >= edges);
  // Faces alone never reach the step's columns; the represented area is the surface's, once.
  CHECK(((faces.uv.select(1, 0) - 32).abs() < 0.5).sum().item<int64_t>() == 0);
  CHECK(s.area.sum().item<double>() == Approx(faces.area.sum().item<double>()).epsilon(1e-4));
}

TEST_CASE("sampler: edge_shift moves near-side edge supports off the silhouette, into their own surface", "[sampler]") {
  // Columns 0..31 at 2 m, 32..64 at 6 m.
  auto depth = torch::full({kH, kW}, 6.0f);
  depth.narrow(1, 0, 32).fill_(2.0f);
  const torch::Tensor img = image();
  SamplerOptions o = fixed(4000);
  o.edge_supports = true;
  const Supports centred = sample_supports(depth, ones(), K(), img, o, 2);
  o.edge_shift = 0.25;
  const Supports shifted = sample_supports(depth, ones(), K(), img, o, 2);
  REQUIRE(shifted.count() == centred.count());
  const auto du = shifted.uv - centred.uv;
  const auto moved = du.abs().gt(1e-6).any(1);
  // Exactly the near side moves (column 31, 2 m beside 6 m), a quarter pixel away from the far side, keeping its
  // depth, colour and footprint; the far side (column 32), the border and the faces stay where they were. Inside
  // the image that is straight left; in the top and bottom rows the far side also lies diagonally, below or above.
  const auto col31 = (centred.uv.select(1, 0) - 31.5).abs().lt(1e-4) & on_pixel_centre(centred.uv);
  REQUIRE(col31.sum().item<int64_t>() == kH);
  CHECK(torch::equal(moved, col31));
  const auto v = centred.uv.select(1, 1), inside = col31 & v.gt(1.0) & v.lt(kH - 1.0);
  REQUIRE(inside.sum().item<int64_t>() == kH - 2);
  CHECK((du.select(1, 0).masked_select(inside) + 0.25).abs().max().item<double>() < 1e-5);
  CHECK(du.select(1, 1).masked_select(inside).abs().max().item<double>() < 1e-6);
  CHECK((du.norm(2, 1).masked_select(col31) - 0.25).abs().max().item<double>() < 1e-5);
  CHECK(torch::equal(shifted.depth, centred.depth));
  CHECK(torch::equal(shifted.color, centred.color));
  CHECK(torch::equal(shifted.area, centred.area));
  // A corner: with row 0's columns 20..31 at 6 m too, the pixel at row 1, column 19 has one farther neighbour,
  // diagonally up and right, and moves a quarter pixel diagonally down and left.
  auto ledge = depth.clone();
  ledge[0].narrow(0, 20, 12).fill_(6.0f);
  o.edge_shift = 0.0;
  const Supports lc = sample_supports(ledge, ones(), K(), img, o, 2);
  o.edge_shift = 0.25;
  const Supports ls = sample_supports(ledge, ones(), K(), img, o, 2);
  const auto at = ((lc.uv.select(1, 0) - 19.5).abs().lt(1e-4) & (lc.uv.select(1, 1) - 1.5).abs().lt(1e-4)).nonzero();
  REQUIRE(at.size(0) == 1);
  const auto step = (ls.uv - lc.uv)[at[0][0].item<int64_t>()];
  const double sx = step[0].item<double>(), sy = step[1].item<double>();
  CHECK(sx == Approx(-0.25 / std::sqrt(2.0)).epsilon(1e-4));
  CHECK(sy == Approx(0.25 / std::sqrt(2.0)).epsilon(1e-4));
  CHECK_THROWS_WITH(config_from_json<SamplerOptions>(nlohmann::json{{"edge_shift", 0.25}}, "test"),
                    Catch::Contains("edge_supports = true"));
  CHECK_THROWS_WITH(
      config_from_json<SamplerOptions>(nlohmann::json{{"edge_supports", true}, {"edge_shift", 0.6}}, "test"),
      Catch::Contains("edge_shift"));
}

TEST_CASE("sampler: edge_behind continues the farther surface under a silhouette", "[sampler]") {
  // Columns 0..31 a flat 2 m; 32..64 a tilted plane (inverse depth affine in the row and the column), 7.4 m at
  // most, whose normal turns away from the camera's axis.
  auto plane = [](double i, double j) { return 1.0 / (1.0 / 6.0 + 0.002 * i - 0.001 * (j - 32)); };
  auto depth = torch::full({kH, kW}, 2.0f);
  for (int64_t i = 0; i < kH; ++i)
    for (int64_t j = 32; j < kW; ++j) depth[i][j] = float(plane(i, j));
  const torch::Tensor img = image();
  SamplerOptions o = fixed(4000);
  o.edge_supports = true;
  const Supports plain = sample_supports(depth, ones(), K(), img, o, 2, true);
  o.edge_behind = 1;
  const Supports s = sample_supports(depth, ones(), K(), img, o, 2, true);
  REQUIRE(s.count() == 4000);
  CHECK(plain.behind == 0);
  CHECK(s.behind == kH);  // counted apart (Supports::behind)
  // The last H supports continue the plane under column 31, the near side, one per row: at the plane's own depth
  // there (each farther neighbour's surface extrapolated), the farther neighbours' mean colour and a pixel's
  // footprint at that depth.
  const auto b = torch::arange(4000 - kH, 4000);
  const auto buv = s.uv.index_select(0, b), bz = s.depth.index_select(0, b);
  CHECK((buv.select(1, 0) - 31.5).abs().max().item<double>() < 1e-5);
  CHECK((buv.select(1, 1) - (torch::arange(kH, torch::kFloat) + 0.5)).abs().max().item<double>() < 1e-5);
  for (int64_t i : {int64_t(1), int64_t(20), kH - 2}) {
    const double z = plane(i, 31);
    CHECK(bz[i].item<double>() == Approx(z).epsilon(1e-5));
    CHECK(s.area[4000 - kH + i].item<double>() == Approx(z * z / (fx * fy)).epsilon(1e-4));
    for (int c = 0; c < 3; ++c) {
      const double mean = img[c].narrow(0, i - 1, 3).select(1, 32).mean().item<double>();
      CHECK(s.color[4000 - kH + i][c].item<double>() == Approx(mean).epsilon(1e-5));
    }
  }
  // The visible supports still stand for the surface's area once; the hidden ones come on top.
  CHECK(s.area.narrow(0, 0, 4000 - kH).sum().item<double>() == Approx(plain.area.sum().item<double>()).epsilon(1e-4));
  // Their normals are the plane's (as a face support's far from the edge), not the near plane's.
  const auto far_face = (plain.uv.select(1, 0) > 50).nonzero()[0][0].item<int64_t>();
  const auto slope_n = plain.normal[far_face], flat_n = plain.normal[0];
  REQUIRE((slope_n - flat_n).abs().max().item<double>() > 0.01);
  const auto bn = s.normal.index_select(0, b).narrow(0, 1, kH - 2);
  CHECK((bn - slope_n).abs().max().item<double>() < 1e-4);
  // Two layers: the second one pixel further in, under column 30, where the plane lies deeper in.
  o.edge_behind = 2;
  const Supports two = sample_supports(depth, ones(), K(), img, o, 2, true);
  const auto tu = two.uv.narrow(0, 4000 - 2 * kH, 2 * kH).select(1, 0);
  CHECK(((tu - 31.5).abs() < 1e-5).sum().item<int64_t>() == kH);
  const auto second = (tu - 30.5).abs() < 1e-5;
  CHECK(second.sum().item<int64_t>() == kH - 2);  // the corner rows also step up or down
  const auto tz = two.depth.narrow(0, 4000 - 2 * kH, 2 * kH).masked_select(second);
  const auto rows = two.uv.narrow(0, 4000 - 2 * kH, 2 * kH).select(1, 1).masked_select(second).floor();
  const auto want = 1.0 / (1.0 / 6.0 + 0.002 * rows.to(torch::kDouble) + 0.002);
  CHECK((tz.to(torch::kDouble) / want - 1).abs().max().item<double>() < 1e-5);
  // At most half the budget goes to edge and hidden supports; a tight budget thins the hidden ones evenly, so every
  // row keeps some (318 edge supports leave 182 of the 192 places of four layers; in the corner rows the places
  // leave the image after two).
  o.edge_behind = 4;
  o.budget = 1000;
  const Supports tight = sample_supports(depth, ones(), K(), img, o, 2, true);
  const auto tv = tight.uv.narrow(0, 1000 - 182, 182).select(1, 1).floor().to(torch::kLong);
  CHECK((tight.depth.narrow(0, 1000 - 182, 182) > 3.0).all().item<bool>());  // the plane: 3.7 m and more
  CHECK(std::get<0>(at::_unique(tv)).size(0) == kH);
  CHECK(tight.behind == 182);
  CHECK_THROWS_WITH(config_from_json<SamplerOptions>(nlohmann::json{{"edge_behind", 1}}, "test"),
                    Catch::Contains("edge_supports = true"));
}

TEST_CASE("sampler: edge_behind stays hidden: thin lines, and planes that come as near as the silhouette",
          "[sampler]") {
  const torch::Tensor img = image();
  SamplerOptions o = fixed(4000);
  o.edge_supports = true;
  o.edge_behind = 3;
  auto hidden = [&](const torch::Tensor& depth, const torch::Tensor& valid, int64_t places) {
    const Supports s = sample_supports(depth, valid, K(), img, o, 2);
    return std::make_pair(s.uv.narrow(0, 4000 - places, places), s.depth.narrow(0, 4000 - places, places));
  };
  // A line one pixel wide (column 20 at 2 m before 6 m): farther on both sides, so one place per pixel, under it.
  auto line = torch::full({kH, kW}, 6.0f);
  line.select(1, 20).fill_(2.0f);
  {
    const auto [uv, z] = hidden(line, ones(), kH + 1);
    CHECK(((uv.narrow(0, 1, kH).select(1, 0) - 20.5).abs() < 1e-5).all().item<bool>());
    CHECK((z.narrow(0, 1, kH) == 6.0f).all().item<bool>());
    // The support before them is not hidden under the line: H places in all, not more.
    CHECK_FALSE((std::abs(uv[0][0].item<double>() - 20.5) < 1e-5 && z[0].item<double>() == 6.0));
  }
  // Two pixels wide (columns 20 and 21): each side's places stop after two, at the far side of the strip.
  auto strip = torch::full({kH, kW}, 6.0f);
  strip.narrow(1, 20, 2).fill_(2.0f);
  {
    const auto [uv, z] = hidden(strip, ones(), 4 * kH);
    CHECK((uv.select(1, 0) >= 20.0).all().item<bool>());
    CHECK((uv.select(1, 0) < 22.0).all().item<bool>());
    CHECK((z == 6.0f).all().item<bool>());
  }
  // A plane that rises towards the silhouette (2.13 m at column 32, extrapolated to 2.07 m under column 31, not
  // apart from its 2 m): each farther neighbour keeps its own depth there. Columns 41.. are invalid.
  auto rise = torch::full({kH, kW}, 2.0f);
  auto valid = ones();
  for (int64_t j = 32; j < kW; ++j)
    if (j <= 40)
      rise.select(1, j).fill_(float(1.0 / (0.47 - 0.012 * (j - 32))));
    else
      valid.select(1, j).zero_();
  o.edge_behind = 1;
  {
    const auto [uv, z] = hidden(rise, valid, kH);
    CHECK((uv.select(1, 0) - 31.5).abs().max().item<double>() < 1e-5);
    CHECK((z / (1.0 / 0.47) - 1).abs().max().item<double>() < 1e-5);
  }
}

TEST_CASE("sampler: pixel mode takes edge_shift and edge_behind too", "[sampler]") {
  auto depth = torch::full({kH, kW}, 6.0f);
  depth.narrow(1, 0, 32).fill_(2.0f);  // the step between columns 31 and 32
  const torch::Tensor img = image();
  SamplerOptions o;
  o.mode = "pixel";
  const Supports plain = sample_supports(depth, ones(), K(), img, o, 2);
  REQUIRE(plain.count() == kH * kW);
  o.edge_behind = 1;
  o.edge_shift = 0.5;
  const Supports s = sample_supports(depth, ones(), K(), img, o, 2, true);
  // One hidden support per row on top, under column 31 at the far side's 6 m.
  REQUIRE(s.count() == kH * kW + kH);
  CHECK(s.behind == kH);
  CHECK(plain.behind == 0);
  CHECK((s.uv.narrow(0, kH * kW, kH).select(1, 0) - 31.5).abs().max().item<double>() < 1e-5);
  CHECK((s.depth.narrow(0, kH * kW, kH) == 6.0f).all().item<bool>());
  // The near side's pixel supports move half a pixel left (inside the image), the others stay at their centres.
  const auto du = s.uv.narrow(0, 0, kH * kW) - plain.uv;
  const auto moved = du.abs().gt(1e-6).any(1);
  const auto col31 = (plain.uv.select(1, 0) - 31.5).abs().lt(1e-4);
  CHECK(torch::equal(moved, col31));
  const auto v = plain.uv.select(1, 1), inside = col31 & v.gt(1.0) & v.lt(kH - 1.0);
  CHECK((du.select(1, 0).masked_select(inside) + 0.5).abs().max().item<double>() < 1e-5);
  CHECK(torch::equal(s.depth.narrow(0, 0, kH * kW), plain.depth));
  CHECK_NOTHROW(config_from_json<SamplerOptions>(
      nlohmann::json{{"mode", "pixel"}, {"edge_behind", 2}, {"edge_shift", 0.5}}, "test"));
}

TEST_CASE("sampler: a band that half the budget cannot cover falls back to the edge pixels, spread evenly",
          "[sampler]") {
  auto depth = torch::full({kH, kW}, 6.0f);
  depth.narrow(1, 0, 32).fill_(2.0f);  // the step between columns 31 and 32; its near band is columns 29..31
  SamplerOptions o = fixed(4000);
  o.edge_supports = true;
  o.edge_band = 2;
  // 3 x 49 band pixels fit in half of 4000 but not in half of 200: the band would leave pixels with no support at
  // all, so the sampler takes the edge pixels alone; those, over budget too, spread over the whole list.
  o.budget = 200;
  const Supports few = sample_supports(depth, ones(), K(), image(), o, 2);
  REQUIRE(few.count() == 200);
  SamplerOptions no_band = o;
  no_band.edge_band = 0;
  CHECK(torch::equal(few.uv, sample_supports(depth, ones(), K(), image(), no_band, 2).uv));
  const auto few_centre = on_pixel_centre(few.uv);
  CHECK(few_centre.sum().item<int64_t>() == 100);
  CHECK((few.uv.select(1, 1).masked_select(few_centre) > kH - 3).any().item<bool>());
}

TEST_CASE("sampler: edge_band widens only the near side of depth edges, over its own surface", "[sampler]") {
  auto depth = torch::full({kH, kW}, 6.0f);
  depth.narrow(1, 0, 32).fill_(2.0f);  // the near side is columns 0..31
  SamplerOptions o = fixed(4000);
  o.edge_supports = true;
  o.edge_band = 2;
  const Supports s = sample_supports(depth, ones(), K(), image(), o, 2);
  REQUIRE(s.count() == 4000);
  const auto u = s.uv.select(1, 0), v = s.uv.select(1, 1);
  const auto on_centre = on_pixel_centre(s.uv);
  const auto face = ~on_centre;
  // Columns 29..31 (the near edge column and two steps into its surface) get a pixel-centre support on every row,
  // and no face support lies between their centres ...
  for (double col : {29.5, 30.5, 31.5}) CHECK(((u - col).abs().lt(1e-4) & on_centre).sum().item<int64_t>() == kH);
  CHECK((face & (u > 29.5 + 1e-4) & (u < 31.5 - 1e-4)).sum().item<int64_t>() == 0);
  // ... while the far side and the border keep faces up to their edge pixels: faces between columns 32.5 and 34.5,
  // and in the outer rows and columns away from the step.
  CHECK((face & (u > 32.5 + 1e-4) & (u < 34.5 - 1e-4)).sum().item<int64_t>() > 0);
  CHECK((face & (v > 0.5) & (v < 2.5) & (u > 40.0)).sum().item<int64_t>() > 0);
  CHECK((face & (u > 0.5) & (u < 2.5)).sum().item<int64_t>() > 0);
  CHECK(((u - 33.5).abs().lt(1e-4) & on_centre & (v > 1.0) & (v < kH - 1.0)).sum().item<int64_t>() == 0);
  // The represented area is still the surface's, once, as without a band.
  SamplerOptions edges_only = o;
  edges_only.edge_band = 0;
  const Supports e = sample_supports(depth, ones(), K(), image(), edges_only, 2);
  CHECK(s.area.sum().item<double>() == Approx(e.area.sum().item<double>()).epsilon(1e-4));
  // The recipe's combination: hidden surface and the shift act on the near band's edge column as without a band.
  o.edge_behind = 3;
  o.edge_shift = 0.5;
  SamplerOptions no_band = o;
  no_band.edge_band = 0;
  const Supports b = sample_supports(depth, ones(), K(), image(), o, 2);
  const Supports nb = sample_supports(depth, ones(), K(), image(), no_band, 2);
  REQUIRE(b.behind > 0);
  CHECK(b.behind == nb.behind);
  CHECK(torch::equal(b.uv.narrow(0, 4000 - b.behind, b.behind), nb.uv.narrow(0, 4000 - nb.behind, nb.behind)));
  const auto bu = b.uv.narrow(0, 0, 4000 - b.behind).select(1, 0), bv = b.uv.narrow(0, 0, 4000 - b.behind).select(1, 1);
  const auto inner = (bv > 1.0) & (bv < kH - 1.0);
  CHECK(((bu - 31.0).abs().lt(1e-4) & inner).sum().item<int64_t>() == kH - 2);
  CHECK(((bu - 30.5).abs().lt(1e-4) & inner).sum().item<int64_t>() == kH - 2);
  CHECK_NOTHROW(config_from_json<SamplerOptions>(
      nlohmann::json{{"edge_supports", true}, {"edge_band", 2}, {"edge_behind", 3}, {"edge_shift", 0.5}}, "test"));
}

TEST_CASE("sampler: no support lands on a depth-discontinuity triangle or in a hole", "[sampler]") {
  auto depth = torch::full({kH, kW}, 1.0f);
  depth.narrow(1, 40, kW - 40).fill_(3.0f);  // a step between columns 39 and 40
  auto valid = ones();
  depth.narrow(0, 10, 8).narrow(1, 5, 10).fill_(std::numeric_limits<float>::quiet_NaN());  // a hole
  const Supports s = sample_supports(depth, valid, K(), image(), fixed(8000), 5);
  CHECK(s.count() == 8000);
  auto u = s.uv.select(1, 0), v = s.uv.select(1, 1);
  // Triangles spanning the step lie between the pixel centres 39.5 and 40.5.
  CHECK(((u > 39.5 + 1e-4) & (u < 40.5 - 1e-4)).sum().item<int64_t>() == 0);
  // Triangles touching a NaN pixel lie within one pixel of the hole.
  CHECK(((u > 4.5 + 1e-4) & (u < 15.5 - 1e-4) & (v > 9.5 + 1e-4) & (v < 18.5 - 1e-4)).sum().item<int64_t>() == 0);
  CHECK(torch::isfinite(s.depth).all().item<bool>());
  // Depth never mixes across the step.
  CHECK(((s.depth > 1.01) & (s.depth < 2.99)).sum().item<int64_t>() == 0);
}

TEST_CASE("sampler: fill_px fills holes near valid depth from around them and leaves far pixels empty", "[sampler]") {
  // A smooth surface, a 12x12 hole in it and an invalid strip 15 pixels wide along the right border.
  const auto u = pixel_centers(kH, kW).select(-1, 0), v = pixel_centers(kH, kW).select(-1, 1);
  const auto truth = 1.0 / (0.5 + 0.003 * u + 0.002 * v);
  auto depth = truth.clone(), valid = ones();
  depth.narrow(0, 10, 12).narrow(1, 20, 12).fill_(std::numeric_limits<float>::quiet_NaN());
  valid.narrow(1, 50, 15).zero_();
  const auto usable = valid * torch::isfinite(depth);

  const FilledDepth f = fill_depth_holes(depth, valid, 8);
  // Valid depth stays bit for bit; the hole (at most 6 px from valid depth) is filled near the surface.
  CHECK(torch::equal(f.depth.masked_select(usable > 0), depth.masked_select(usable > 0)));
  const auto hole = f.depth.narrow(0, 10, 12).narrow(1, 20, 12), hole_truth = truth.narrow(0, 10, 12).narrow(1, 20, 12);
  CHECK(f.valid.narrow(0, 10, 12).narrow(1, 20, 12).min().item<float>() == 1.0f);
  CHECK(((hole - hole_truth).abs() / hole_truth).max().item<double>() < 0.01);
  // The strip: columns 50-57 lie within 8 px of valid depth and are filled, 58-64 stay invalid.
  CHECK(f.valid.narrow(1, 50, 8).min().item<float>() == 1.0f);
  CHECK(f.valid.narrow(1, 58, 7).max().item<float>() == 0.0f);
  CHECK(f.depth.narrow(1, 58, 7).abs().max().item<float>() == 0.0f);
  CHECK(f.filled == 144 + 8 * kH);
  CHECK(torch::isfinite(f.depth).all().item<bool>());
  // Filled depth is a blend: never outside the range of the valid depth.
  const auto valid_depth = depth.masked_select(usable > 0);
  const auto strip = f.depth.narrow(1, 50, 8);
  CHECK(strip.min().item<double>() >= valid_depth.min().item<double>());
  CHECK(strip.max().item<double>() <= valid_depth.max().item<double>());

  // Off, or nothing to fill from: unchanged; a negative distance is refused.
  const FilledDepth off = fill_depth_holes(depth, valid, 0);
  CHECK(off.filled == 0);
  CHECK(torch::equal(off.valid, usable));
  const FilledDepth none = fill_depth_holes(depth, torch::zeros({kH, kW}), 8);
  CHECK(none.filled == 0);
  CHECK(none.valid.max().item<float>() == 0.0f);
  CHECK_THROWS_WITH(fill_depth_holes(depth, valid, -1), Catch::Contains("max_px"));
  const FilledDepth whole = fill_depth_holes(truth, ones(), 8);  // nothing to fill
  CHECK(whole.filled == 0);
  CHECK(torch::equal(whole.depth, truth.to(torch::kFloat32)));

  // The distance is Chebyshev: one valid pixel with max_px = 2 fills exactly the 5x5 square around it, with its depth.
  auto lone = torch::zeros({9, 9});
  lone[4][4] = 3.0f;
  const FilledDepth square = fill_depth_holes(lone, lone > 0, 2);
  CHECK(square.filled == 24);
  CHECK(square.valid.narrow(0, 2, 5).narrow(1, 2, 5).min().item<float>() == 1.0f);
  CHECK(square.valid.sum().item<float>() == 25.0f);
  CHECK(square.depth.narrow(0, 2, 5).narrow(1, 2, 5).sub(3.0f).abs().max().item<float>() < 1e-5f);

  // The blend is in log depth: a gap between 1 m and 100 m in a one-row image fills symmetrically in log depth
  // (the two filled depths multiply to 100, the nearer stays below 10 m), where a linear blend would give 26 and 75.
  auto row = torch::tensor({1.0f, 0.0f, 0.0f, 100.0f}).reshape({1, 4});
  const FilledDepth gap = fill_depth_holes(row, row > 0, 2);
  CHECK(gap.filled == 2);
  const double near = gap.depth[0][1].item<double>(), far = gap.depth[0][2].item<double>();
  CHECK(near * far == Approx(100.0).epsilon(1e-4));
  CHECK(near < 10.0);

  // The sampler: without filling no support lands in the hole; with fill_px = 8 supports cover it at the
  // surface's depth, and none reach the strip's far part.
  auto in_hole = [](const Supports& s) {
    const auto su = s.uv.select(1, 0), sv = s.uv.select(1, 1);
    return (su > 20.5) & (su < 31.5) & (sv > 10.5) & (sv < 21.5);
  };
  const Supports plain = sample_supports(depth, valid, K(), image(), fixed(8000), 3);
  CHECK(in_hole(plain).sum().item<int64_t>() == 0);
  SamplerOptions filled = fixed(8000);
  filled.fill_px = 8;
  const Supports s = sample_supports(depth, valid, K(), image(), filled, 3);
  CHECK(s.count() == 8000);
  CHECK(in_hole(s).sum().item<int64_t>() > 50);
  // Inside the hole the fill interpolates; beyond the strip's edge it only continues the border's depth.
  const auto expected = 1.0 / (0.5 + 0.003 * s.uv.select(1, 0) + 0.002 * s.uv.select(1, 1));
  CHECK(((s.depth - expected).abs() / expected).masked_select(in_hole(s)).max().item<double>() < 0.03);
  CHECK((s.uv.select(1, 0) > 57.5 + 1e-4).sum().item<int64_t>() == 0);
  // Budgets that count valid depth count the filled pixels too.
  SamplerOptions sa;
  sa.budget_mode = "solid_angle";
  sa.density = 2000;
  const int64_t plain_budget = resolve_budget(sa, depth, valid, K());
  sa.fill_px = 8;
  CHECK(resolve_budget(sa, depth, valid, K()) > plain_budget);
}

TEST_CASE("sampler: the same seed gives identical supports, another seed different ones", "[sampler]") {
  auto depth = 1.0 + torch::rand({kH, kW});
  auto img = image();
  const Supports a = sample_supports(depth, ones(), K(), img, fixed(3000), 11);
  const Supports b = sample_supports(depth, ones(), K(), img, fixed(3000), 11);
  const Supports c = sample_supports(depth, ones(), K(), img, fixed(3000), 12);
  CHECK(torch::equal(a.uv, b.uv));
  CHECK(torch::equal(a.color, b.color));
  CHECK_FALSE(torch::equal(a.uv, c.uv));
}

TEST_CASE("sampler: pixel and vertex_face modes, and adaptive budgets", "[sampler]") {
  auto depth = torch::full({kH, kW}, 2.0f);
  auto valid = ones();
  valid.narrow(0, 0, 12).zero_();  // top quarter invalid (sky)
  SamplerOptions px;
  px.mode = "pixel";
  const Supports p = sample_supports(depth, valid, K(), image(), px);
  CHECK(p.count() == (kH - 12) * kW);
  CHECK(p.uv[0][0].item<float>() == 0.5f);
  CHECK(p.uv[0][1].item<float>() == 12.5f);

  SamplerOptions vf = fixed(2000);
  vf.mode = "vertex_face";
  auto img = torch::zeros({3, kH, kW});
  img.narrow(2, 30, 4).fill_(1.0f);  // strong vertical edges at columns 29/30 and 33/34
  const Supports v = sample_supports(depth, valid, K(), img, vf);
  CHECK(v.count() == 2000);
  // The 1300 vertex supports come first and include every pixel of the 4 edge columns (37 valid rows
  // each), which have the strongest gradients.
  auto vert = v.uv.narrow(0, 0, 1300).select(1, 0);
  auto on_edge = (vert == 29.5f) | (vert == 30.5f) | (vert == 33.5f) | (vert == 34.5f);
  CHECK(on_edge.sum().item<int64_t>() == 4 * 37);

  SamplerOptions pp;
  pp.budget_mode = "per_pixel";
  pp.density = 0.5;
  pp.min_budget = 1;
  CHECK(resolve_budget(pp, depth, valid, K()) == (kH * kW + 1) / 2);
  SamplerOptions sa;
  sa.budget_mode = "solid_angle";
  sa.density = 20000.0;
  sa.min_budget = 1;
  const int64_t full = resolve_budget(sa, depth, ones(), K());
  const int64_t part = resolve_budget(sa, depth, valid, K());
  CHECK(full > 0);
  CHECK(static_cast<double>(part) / full == Approx(37.0 / 49.0).margin(0.05));  // the top 12 rows are sky
  CHECK(sample_supports(depth, valid, K(), image(), sa).count() == part);
}

TEST_CASE("sampler: the detail budget gives a plain flat wall few supports and a cluttered scene many", "[sampler]") {
  SamplerOptions o;
  o.budget_mode = "detail";
  o.density = 1.0;
  o.min_budget = 1;
  // A plain fronto-parallel wall: no colour gradient, zero curvature, so every block gets the floor.
  const auto wall_depth = torch::full({kH, kW}, 3.0f);
  const auto plain = torch::full({3, kH, kW}, 0.5f);
  const int64_t wall = resolve_budget(o, wall_depth, ones(), K(), plain);
  CHECK(wall == static_cast<int64_t>(std::llround(o.detail_floor * kH * kW)));
  // Clutter of the same size: random colours on a bumpy surface earn the full density.
  torch::manual_seed(3);
  const auto bumpy = 2.0f + 0.5f * torch::rand({kH, kW});
  const int64_t cluttered = resolve_budget(o, bumpy, ones(), K(), torch::rand({3, kH, kW}));
  CHECK(cluttered == kH * kW);
  CHECK(sample_supports(bumpy, ones(), K(), torch::rand({3, kH, kW}), o).count() == cluttered);
  CHECK_THROWS_AS(resolve_budget(o, wall_depth, ones(), K()), Error);  // needs the image

  // Half plain, half textured on one plane: supports crowd the textured half, and the represented areas
  // still add up to the surface.
  auto half = torch::full({3, kH, kW}, 0.5f);
  half.narrow(2, 32, kW - 32).copy_(torch::rand({3, kH, kW - 32}));
  const auto weights = detail_weights(wall_depth, ones(), half, o);
  CHECK(weights.narrow(1, 0, 24).max().item<float>() == Approx(o.detail_floor));
  CHECK(weights.narrow(1, 40, kW - 40).min().item<float>() == Approx(1.0));
  const Supports s = sample_supports(wall_depth, ones(), K(), half, o, 5);
  const auto hist = column_histogram(s, 4);
  CHECK(hist[3] > 4 * hist[0]);
  const double area = ((kW - 1) * 3.0 / fx) * ((kH - 1) * 3.0 / fy);
  CHECK(s.area.sum().item<double>() == Approx(area).epsilon(0.02));
}

TEST_CASE("sampler: all-invalid depth is a clear error", "[sampler]") {
  auto depth = torch::full({kH, kW}, std::numeric_limits<float>::quiet_NaN());
  CHECK_THROWS_WITH(sample_supports(depth, ones(), K(), image(), fixed(100)), Catch::Contains("no valid triangle"));
  SamplerOptions px;
  px.mode = "pixel";
  CHECK_THROWS_WITH(sample_supports(torch::zeros({kH, kW}), ones(), K(), image(), px),
                    Catch::Contains("no valid pixel"));
  CHECK_THROWS_WITH(sample_supports(torch::ones({kH, kW}), ones(), K(), torch::rand({3, 8, 8}), fixed(10)),
                    Catch::Contains("image must be [3, H, W]"));
  // Pixel mode has no budget, so an image above the support limit is refused before anything is allocated.
  const int64_t side = 2048;  // 4.19M pixels
  CHECK_THROWS_WITH(
      sample_supports(torch::ones({side, side}), torch::ones({side, side}), K(), torch::zeros({3, side, side}), px),
      Catch::Contains("pixel mode places one support per valid pixel: 4194304 at 2048x2048") &&
          Catch::Contains("--max-gaussians"));
}

TEST_CASE("sampler: every support carries the plane's normal, facing the camera, in every mode", "[sampler]") {
  // The plane n.X = -2 with n facing the camera (n.X < 0): depth z = -2 / (n . ray).
  const double nx = 0.3, ny = -0.2, nz = -1.0, nl = std::sqrt(nx * nx + ny * ny + nz * nz);
  auto jj = torch::arange(kW, torch::kFloat64).add(0.5).sub(cx).div(fx).unsqueeze(0).expand({kH, kW});
  auto ii = torch::arange(kH, torch::kFloat64).add(0.5).sub(cy).div(fy).unsqueeze(1).expand({kH, kW});
  auto depth = (-2.0 * nl / (nx * jj + ny * ii + nz)).to(torch::kFloat32);
  REQUIRE(depth.min().item<float>() > 0);
  const auto expected = torch::tensor({nx / nl, ny / nl, nz / nl});
  // Normals are only filled on request.
  CHECK_FALSE(sample_supports(depth, ones(), K(), image(), fixed(1500), 3).normal.defined());
  SamplerOptions area = fixed(1500), pixel = fixed(0), vf = fixed(1500);
  pixel.mode = "pixel";
  vf.mode = "vertex_face";
  for (const SamplerOptions& o : {area, pixel, vf}) {
    const Supports s = sample_supports(depth, ones(), K(), image(), o, 3, true);
    REQUIRE(s.normal.sizes() == torch::IntArrayRef({s.count(), 3}));
    CHECK(torch::allclose(s.normal, expected.expand({s.count(), 3}), 1e-4, 1e-4));
  }
  // A lone valid pixel has no surface around it: its normal points back along its ray.
  auto valid = torch::zeros({kH, kW});
  valid[10][20] = 1;
  const Supports lone = sample_supports(torch::full({kH, kW}, 3.0f), valid, K(), image(), pixel, 0, true);
  REQUIRE(lone.count() == 1);
  auto ray = torch::tensor({(20.5 - cx) / fx, (10.5 - cy) / fy, 1.0}, torch::kFloat32);
  CHECK(torch::allclose(lone.normal[0], -ray / ray.norm(), 1e-5, 1e-6));
}

TEST_CASE("sampler: along a crease the normal is the area-weighted mean of both faces", "[sampler]") {
  // A back wall at z = 5 (normal (0,0,-1)) meets a floor at y = 1.2 below the camera (normal (0,-1,0)); depth is
  // continuous across the crease, so its triangles are accepted on both sides.
  auto v = torch::arange(kH, torch::kFloat32).add(0.5).sub(cy).div(fy).unsqueeze(1).expand({kH, kW});
  auto depth = torch::minimum(torch::full({kH, kW}, 5.0f), 1.2f / v.clamp_min(1e-3f)).contiguous();
  SamplerOptions px = fixed(0);
  px.mode = "pixel";
  const Supports s = sample_supports(depth, ones(), K(), image(), px, 0, true);
  REQUIRE(s.count() == kH * kW);
  auto n = s.normal;
  CHECK(torch::allclose(n.norm(2, 1), torch::ones({s.count()}), 1e-5, 1e-5));
  CHECK(n.select(1, 0).abs().max().item<float>() < 1e-4f);  // no sideways tilt anywhere
  const auto wall = (n.select(1, 2) + 1).abs() < 1e-4, floor = (n.select(1, 1) + 1).abs() < 1e-4;
  const auto blend = ~wall & ~floor;
  // Exactly the crease's pixels blend the two faces, pointing between them toward the camera.
  const int64_t blended = blend.sum().item<int64_t>();
  CHECK(blended >= kW);
  CHECK(blended <= 3 * kW);
  CHECK((n.select(1, 1).masked_select(blend) < 0).all().item<bool>());
  CHECK((n.select(1, 2).masked_select(blend) < 0).all().item<bool>());
  // Far from the crease, rows are pure wall (top) and pure floor (bottom).
  CHECK(wall.view({kH, kW})[2].all().item<bool>());
  CHECK(floor.view({kH, kW})[kH - 2].all().item<bool>());
  // Area mode reads the same per-pixel normals: every support's normal is one of the pixel-mode normals.
  SamplerOptions area = fixed(4000);
  const Supports a = sample_supports(depth, ones(), K(), image(), area, 5, true);
  auto ia = a.uv.select(1, 1).floor().clamp(0, kH - 1).to(torch::kLong),
       ja = a.uv.select(1, 0).floor().clamp(0, kW - 1).to(torch::kLong);
  CHECK(torch::equal(a.normal, n.index_select(0, ia * kW + ja)));
}

TEST_CASE("sampler: base Gaussians follow the scene normalization", "[sampler]") {
  auto depth = torch::full({kH, kW}, 2.0f);
  depth.narrow(1, 0, 8).fill_(0.5f);
  SamplerOptions o = fixed(1000);
  const Supports s = sample_supports(depth, ones(), K(), image(), o, 2, true);
  const BaseGaussians b = make_base_gaussians(s);
  CHECK(b.depth_factor == Approx(1.0 / s.depth.min().item<double>()));
  CHECK(b.z_n.min().item<float>() == Approx(1.0f));
  CHECK(torch::allclose(b.scale_n, torch::sqrt(s.area) * b.depth_factor));
  CHECK(b.color.min().item<float>() >= 0.01f);
  CHECK(b.color.max().item<float>() <= 0.99f);
  CHECK((b.opacity == 0.5f).all().item<bool>());
  CHECK(torch::equal(b.normal, s.normal));
}
