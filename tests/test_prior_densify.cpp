// The sparse prior's densification (prior.sparse.densify, far): a useless prior leaves the prompt-only result, a
// good one is at least as good as the fit, confidence falls with distance, the far rule, errors and options.
#include <catch2/catch.hpp>

#include <torch/torch.h>

#include "core/config.h"
#include "core/error.h"
#include "prior/depth_prior.h"

namespace isplat::test_prior_densify {

// A room seen head-on: a back wall at 4 m (grey-blue), a box in front at 1.5 m (red), a slanted floor strip; the
// colours change exactly where the depth does.
struct Scene {
  torch::Tensor image, depth;
};
Scene room(int64_t H, int64_t W) {
  Scene s{torch::empty({3, H, W}), torch::empty({H, W})};
  for (int64_t y = 0; y < H; ++y)
    for (int64_t x = 0; x < W; ++x) {
      const bool box = x >= W / 3 && x < 2 * W / 3 && y >= H / 4 && y < 3 * H / 4;
      const bool floor = y >= 4 * H / 5;
      const double z = box ? 1.5 : floor ? 2.0 + 2.0 * double(H - 1 - y) / (H / 5.0) : 4.0 + 0.01 * x;
      s.depth[y][x] = z;
      const float rgb[3] = {box     ? 0.8f
                            : floor ? 0.4f
                                    : 0.3f,
                            box     ? 0.2f
                            : floor ? 0.35f
                                    : 0.4f,
                            box     ? 0.2f
                            : floor ? 0.2f
                                    : 0.6f};
      for (int c = 0; c < 3; ++c) s.image[c][y][x] = rgb[c];
    }
  return s;
}

double abs_rel(const torch::Tensor& pred, const torch::Tensor& truth) {
  return ((pred - truth).abs() / truth).mean().item<double>();
}

TEST_CASE("densify: with a useless prior, blend is the prompt-only densification", "[prior][densify_prior]") {
  const int64_t H = 72, W = 96;
  const Scene s = room(H, W);
  const auto prompts = draw_prompts(s.depth, torch::ones({H, W}), 500, 0.0, 3);
  torch::manual_seed(0);
  const auto useless = 0.5 + 5.0 * torch::rand({H, W});  // no shape at all: a new depth at every pixel
  for (double range : {1.0, 0.1}) {                      // the default, and a narrow colour range (more edge-aware)
    SparsePriorOptions o;
    o.color_range = range;
    o.densify = "image";
    const SparseDensity image = densify_prompts(s.image, {}, prompts, o);
    o.densify = "blend";
    const SparseDensity blend = densify_prompts(s.image, useless, prompts, o);
    CHECK(blend.prior_weight.max().item<double>() == 0.0);
    CHECK(torch::equal(blend.depth, image.depth));  // exactly
    CHECK(torch::equal(blend.confidence, image.confidence));
    // The prompt-only floor beats today's fit of a constant (mono = none), and is edge-aware with a narrow range.
    o.densify = "fit";
    const SparseDensity constant = densify_prompts(s.image, torch::ones({H, W}), prompts, o);
    INFO("range " << range << ": image-guided " << abs_rel(image.depth, s.depth) << ", constant fit "
                  << abs_rel(constant.depth, s.depth));
    CHECK(abs_rel(image.depth, s.depth) <= abs_rel(constant.depth, s.depth));
    if (range < 1) {
      CHECK(abs_rel(image.depth, s.depth) < 0.7 * abs_rel(constant.depth, s.depth));
      CHECK(abs_rel(image.depth, s.depth) < 0.03);
    }
  }
}

TEST_CASE("densify: with a good prior, blend is at least as good as today's fit", "[prior][densify_prior]") {
  const int64_t H = 72, W = 96;
  const Scene s = room(H, W);
  const auto prompts = draw_prompts(s.depth, torch::ones({H, W}), 500, 0.0, 5);
  const auto good = 3.0 / s.depth;  // the right shape in inverse depth, wrong scale and shift
  SparsePriorOptions o;
  o.densify = "fit";
  const SparseDensity fit = densify_prompts(s.image, 1.0 / (good + 0.2), prompts, o);
  o.densify = "blend";
  const SparseDensity blend = densify_prompts(s.image, 1.0 / (good + 0.2), prompts, o);
  o.densify = "image";
  const SparseDensity image = densify_prompts(s.image, {}, prompts, o);
  const double e_fit = abs_rel(fit.depth, s.depth), e_blend = abs_rel(blend.depth, s.depth),
               e_image = abs_rel(image.depth, s.depth);
  INFO("fit " << e_fit << ", blend " << e_blend << ", image " << e_image);
  CHECK(e_fit < e_image);                 // the good prior helps ...
  CHECK(e_blend <= e_fit * 1.02 + 1e-5);  // ... and blend keeps what it gives (within 2%)
  CHECK(blend.prior_weight.mean().item<double>() > 0.9);
  // fit keeps today's alignment exactly
  SparsePriorOptions today;
  CHECK(torch::equal(fit.depth, align_to_prompts(1.0 / (good + 0.2), prompts, today)));
}

TEST_CASE("densify: confidence falls with the distance to the prompts, and the far rule holds",
          "[prior][densify_prior]") {
  const int64_t H = 48, W = 96;
  const Scene s = room(H, W);
  auto left = torch::zeros({H, W});
  left.narrow(1, 0, W / 4).fill_(1);  // a sensor that returned only the left quarter
  const auto prompts = draw_prompts(s.depth, left, 300, 0.0, 1);
  SparsePriorOptions o;
  o.densify = "image";
  const SparseDensity keep = densify_prompts(s.image, {}, prompts, o);
  const auto row = keep.confidence[H / 2];
  for (int64_t x = W / 4 + 2; x + 4 < W; x += 4) CHECK(row[x + 4].item<double>() <= row[x].item<double>());
  CHECK(row[W / 8].item<double>() > 0.3);
  CHECK(row[W - 1].item<double>() < 1e-6);
  CHECK(keep.distance[H / 2][W - 1].item<double>() > keep.distance[H / 2][W / 2].item<double>());
  CHECK((keep.depth > 0).all().item<bool>());
  o.far = "drop";
  const SparseDensity drop = densify_prompts(s.image, {}, prompts, o);
  const auto far = keep.distance > o.far_spacings;
  REQUIRE(far.any().item<bool>());
  CHECK((drop.depth.masked_select(far) == 0).all().item<bool>());
  CHECK(torch::equal(drop.depth.masked_select(~far), keep.depth.masked_select(~far)));
  CHECK((drop.confidence.masked_select(far) == 0).all().item<bool>());
  // behind: a far pixel survives only at or beyond the farthest supported depth near it
  o.far = "behind";
  const SparseDensity behind = densify_prompts(s.image, {}, prompts, o);
  const auto kept = far & (behind.depth > 0);
  const auto dropped = far & (behind.depth == 0);
  CHECK(torch::equal(behind.depth.masked_select(~far), keep.depth.masked_select(~far)));
  CHECK((dropped | kept).equal(far));
  if (dropped.any().item<bool>()) {
    CHECK((keep.depth.masked_select(dropped) < keep.depth.masked_select(~far).max()).all().item<bool>());
  }
}

TEST_CASE("densify: invalid or empty prompts give clear errors", "[prior][densify_prior]") {
  const int64_t H = 24, W = 32;
  const Scene s = room(H, W);
  SparsePriorOptions o;
  o.densify = "image";
  CHECK_THROWS_WITH(densify_prompts(s.image, {}, torch::zeros({0, 3}), o), Catch::Contains("at least 3 prompts"));
  CHECK_THROWS_WITH(densify_prompts(s.image, {}, torch::zeros({5, 2}), o), Catch::Contains("[P, 3] (u, v, z)"));
  auto p = draw_prompts(s.depth, torch::ones({H, W}), 20, 0.0, 1);
  auto negative = p.clone();
  negative[3][2] = -1.0;
  CHECK_THROWS_WITH(densify_prompts(s.image, {}, negative, o), Catch::Contains("not finite and positive"));
  auto nan = p.clone();
  nan[2][2] = std::numeric_limits<float>::quiet_NaN();
  CHECK_THROWS_WITH(densify_prompts(s.image, {}, nan, o), Catch::Contains("not finite and positive"));
  auto outside = p.clone();
  outside[0][0] = W + 5.0;
  CHECK_THROWS_WITH(densify_prompts(s.image, {}, outside, o), Catch::Contains("outside the 32x24 image"));
  o.densify = "blend";
  CHECK_THROWS_WITH(densify_prompts(s.image, {}, p, o), Catch::Contains("needs a monocular depth"));
  // through the prior: a frame without valid depth to draw from
  PriorOptions po;
  po.type = "sparse";
  po.sparse.mono = "none";
  po.sparse.densify = "blend";
  PriorInput in;
  in.image = s.image;
  in.depth = torch::zeros({H, W});
  CHECK_THROWS_WITH(make_depth_prior(po)->predict(in), Catch::Contains("no valid pixel"));
}

TEST_CASE("densify: the options are validated, and mono = dataset gives the true or a warped shape",
          "[prior][densify_prior][config]") {
  auto parse = [](const nlohmann::json& sparse) {
    ConfigDocument doc;
    doc.json = {{"sparse", sparse}};
    doc.origin[""] = "test.json";
    PriorOptions o;
    apply_config(doc, o);
    return o;
  };
  CHECK(parse({{"densify", "blend"}, {"far", "drop"}}).sparse.far == "drop");
  CHECK_THROWS_WITH(parse({{"densify", "mix"}}), Catch::Contains("densify"));
  CHECK_THROWS_WITH(parse({{"far", "hide"}}), Catch::Contains("far"));
  CHECK_THROWS_WITH(parse({{"far_spacings", 0}}), Catch::Contains("far_spacings"));
  CHECK_THROWS_WITH(parse({{"color_range", 0}}), Catch::Contains("color_range"));
  CHECK_THROWS_WITH(parse({{"mono_warp", 0.3}}), Catch::Contains("prior.sparse.mono = dataset"));
  CHECK(parse({{"mono", "dataset"}, {"mono_warp", 0.3}}).sparse.mono_warp == 0.3);
  const int64_t H = 48, W = 64;
  const Scene s = room(H, W);
  PriorOptions o = parse({{"mono", "dataset"}, {"densify", "fit"}});
  o.type = "sparse";
  PriorInput in;
  in.image = s.image;
  in.depth = s.depth;
  in.seed = 4;
  const PriorOutput right = make_depth_prior(o)->predict(in);
  CHECK(abs_rel(right.depth, s.depth) < 1e-3);  // the true shape: the fit is exact
  REQUIRE(right.confidence.defined());
  o.sparse.mono_warp = 0.5;
  const PriorOutput warped = make_depth_prior(o)->predict(in);
  CHECK(abs_rel(warped.depth, s.depth) > 2 * abs_rel(right.depth, s.depth));
  CHECK(torch::equal(warped.depth, make_depth_prior(o)->predict(in).depth));  // deterministic per frame
  // the evaluator's unperturbed depth is the shape, when given
  in.reference_depth = s.depth;
  in.depth = s.depth * (torch::rand({H, W}) > 0.3).to(torch::kFloat32);
  o.sparse.mono_warp = 0;
  CHECK(abs_rel(make_depth_prior(o)->predict(in).depth, s.depth) < 1e-3);
}

}  // namespace isplat::test_prior_densify
