// Sensor-realistic depth (perturb.sensor): each effect at the requested strength on constructed depth maps, the
// kinect preset, determinism, and the schema (a preset with values is refused, sweeps reach the sensor keys).
#include <catch2/catch.hpp>

#include <cmath>

#include "core/config.h"
#include "core/error.h"
#include "data/perturb.h"
#include "data/sensor.h"
#include "eval/eval_config.h"
#include "geometry/color.h"

namespace sensor_test {
using namespace isplat;

torch::Tensor K_of(double f, int64_t W, int64_t H) {
  return torch::tensor({f, 0.0, 0.5 * W, 0.0, f, 0.5 * H, 0.0, 0.0, 1.0}).reshape({3, 3});
}

// Near surface (z = 1) on the columns left of `edge`, far surface (z = 3) from it on.
torch::Tensor step(int64_t W, int64_t H, int64_t edge) {
  auto z = torch::full({H, W}, 3.0f);
  z.narrow(1, 0, edge).fill_(1.0f);
  return z;
}

SensorOptions only(const std::function<void(SensorOptions&)>& set) {
  SensorOptions o;
  set(o);
  return o;
}

TEST_CASE("sensor: drop-outs beyond range, on dark surfaces and behind occluders", "[data][perturb][sensor]") {
  const int64_t W = 40, H = 30;
  const auto ones = torch::ones({H, W});
  // Range: a ramp from 1 to 5 m; nothing beyond 3 m returns.
  const auto ramp = torch::linspace(1, 5, W).repeat({H, 1});
  const SensorDepth r = apply_sensor(ramp, ones, only([](SensorOptions& o) { o.max_range = 3.0; }), 1);
  CHECK(torch::equal(r.valid > 0, ramp <= 3.0));
  CHECK(torch::equal(r.depth, ramp * (ramp <= 3.0)));
  // Dark: the left half at linear luminance 0.005, the right at 0.5; a 0.01 threshold drops the left half exactly.
  auto image = torch::full({3, H, W}, 0.5f);
  image.narrow(2, 0, W / 2).fill_(0.005f);
  const SensorDepth d =
      apply_sensor(ones * 2, ones, only([](SensorOptions& o) { o.dark = 0.01; }), 1, linear_to_srgb(image));
  CHECK(d.valid.narrow(1, 0, W / 2).sum().item<double>() == 0);
  CHECK(d.valid.narrow(1, W / 2, W / 2).sum().item<double>() == H * W / 2);
  CHECK_THROWS_WITH(apply_sensor(ones, ones, only([](SensorOptions& o) { o.dark = 0.01; }), 1),
                    Catch::Contains("sensor.dark needs the source image"));
  // Shadow: the far surface's n + 1 columns next to the edge (the far edge pixel and n beyond) lose their returns;
  // the near surface keeps all of its own.
  for (int64_t n : {1, 3}) {
    const SensorDepth s = apply_sensor(step(W, H, 20), ones, only([&](SensorOptions& o) { o.shadow_px = n; }), 1);
    CHECK(s.valid.narrow(1, 0, 20).sum().item<double>() == 20 * H);
    CHECK(s.valid.narrow(1, 20, n + 1).sum().item<double>() == 0);
    CHECK(s.valid.sum().item<double>() == (W - n - 1) * H);
  }
}

TEST_CASE("sensor: grazing angles lose their returns at the requested angle", "[data][perturb][sensor]") {
  const int64_t W = 64, H = 48;
  const double f = 50;
  const auto K = K_of(f, W, H);
  // A plane n . P = 1 with its normal 70 degrees from the optical axis: the incidence angle varies across the image.
  const double a = 70.0 * M_PI / 180;
  const auto u = (torch::arange(W).to(torch::kFloat64) + 0.5 - W / 2.0) / f;
  const auto v = (torch::arange(H).to(torch::kFloat64) + 0.5 - H / 2.0) / f;
  const auto rx = u.repeat({H, 1}), ry = v.unsqueeze(1).repeat({1, W});
  const auto ndotr = std::sin(a) * rx + std::cos(a);  // n = (sin a, 0, cos a), r = (x, y, 1)
  const auto z = (1.0 / ndotr).to(torch::kFloat32);
  const auto ok = (ndotr > 0.05).to(torch::kFloat32);
  const auto truth = torch::acos(ndotr.abs() / torch::sqrt(rx * rx + ry * ry + 1)) * 180 / M_PI;
  const auto angle = incidence_deg(z * ok, ok, K);
  const auto inner = torch::isfinite(angle);
  CHECK(inner.sum().item<double>() > 0.9 * ok.sum().item<double>());
  CHECK((angle - truth).abs().index({inner}).max().item<double>() < 0.2);
  for (double limit : {60.0, 72.0}) {
    const SensorDepth g = apply_sensor(z * ok, ok, only([&](SensorOptions& o) { o.grazing_deg = limit; }), 1, {}, K);
    const auto decided = inner.logical_and((truth - limit).abs() > 0.5);  // away from the threshold
    CHECK(torch::equal((g.valid > 0).index({decided}), (truth <= limit).index({decided})));
    CHECK(g.valid.sum().item<double>() > 0);
    CHECK(g.valid.sum().item<double>() < ok.sum().item<double>());
  }
  CHECK_THROWS_WITH(apply_sensor(z, ok, only([](SensorOptions& o) { o.grazing_deg = 60; }), 1),
                    Catch::Contains("grazing_deg needs the source camera's intrinsics"));
}

TEST_CASE("sensor: flying pixels, noise growing with z^2, quantization and misregistration",
          "[data][perturb][sensor]") {
  const int64_t W = 200, H = 200;
  const auto ones = torch::ones({H, W});
  // Flying pixels: about the requested share of the two edge columns take a depth between the surfaces; nothing else
  // moves.
  const auto z = step(W, H, 100);
  const SensorDepth fl = apply_sensor(z, ones, only([](SensorOptions& o) { o.flying = 0.3; }), 5);
  const auto moved = fl.depth != z;
  CHECK(moved.narrow(1, 0, 99).sum().item<int64_t>() == 0);
  CHECK(moved.narrow(1, 101, 99).sum().item<int64_t>() == 0);
  const double share = moved.sum().item<double>() / (2.0 * H);
  CHECK(share == Approx(0.3).margin(0.06));
  const auto fly = fl.depth.index({moved});
  CHECK(fly.min().item<double>() >= 1.0);
  CHECK(fly.max().item<double>() <= 3.0);
  // Noise: sigma = k z^2 on a plane at 2 m and one at 4 m.
  auto planes = torch::full({H, W}, 2.0f);
  planes.narrow(0, H / 2, H / 2).fill_(4.0f);
  const double k = 0.01;
  const SensorDepth nz = apply_sensor(planes, ones, only([&](SensorOptions& o) { o.noise_z2 = k; }), 7);
  const auto err = nz.depth - planes;
  CHECK(err.narrow(0, 0, H / 2).std().item<double>() == Approx(k * 4).epsilon(0.05));
  CHECK(err.narrow(0, H / 2, H / 2).std().item<double>() == Approx(k * 16).epsilon(0.05));
  CHECK(err.mean().item<double>() == Approx(0).margin(0.01));
  // Quantization: every returned 1/z is a multiple of the step, within half a step of the truth.
  const auto ramp = torch::linspace(0.5, 6, W).repeat({H, 1});
  const double q = 0.003;
  const SensorDepth qz = apply_sensor(ramp, ones, only([&](SensorOptions& o) { o.disparity_step = q; }), 1);
  const auto level = 1.0 / qz.depth.to(torch::kFloat64) / q;
  CHECK((level - torch::round(level)).abs().max().item<double>() < 1e-3);
  CHECK((1.0 / qz.depth - 1.0 / ramp).abs().max().item<double>() <= 0.5 * q * 1.001);
  CHECK(std::get<0>(torch::unique_consecutive(qz.depth.select(0, 0))).numel() < W);  // steps, not a ramp
  // Misregistration: the depth map moves 2 px right and 1 px down; the uncovered border has no depth.
  const auto any = torch::rand({H, W}) + 1;
  const SensorDepth sh = apply_sensor(any, ones, only([](SensorOptions& o) { o.shift_x = 2, o.shift_y = 1; }), 1);
  CHECK(torch::equal(sh.depth.narrow(0, 1, H - 1).narrow(1, 2, W - 2), any.narrow(0, 0, H - 1).narrow(1, 0, W - 2)));
  CHECK(sh.valid.narrow(1, 0, 2).sum().item<double>() == 0);
  CHECK(sh.valid.narrow(0, 0, 1).sum().item<double>() == 0);
  CHECK(sh.valid.sum().item<double>() == (H - 1) * (W - 2));
}

TEST_CASE("sensor: the kinect preset, determinism and the schema", "[data][perturb][sensor]") {
  SensorOptions kinect;
  kinect.preset = "kinect";
  CHECK(kinect.any());
  CHECK_FALSE(SensorOptions{}.any());
  const SensorOptions r = kinect.resolved();
  CHECK(r.grazing_deg == 75.0);
  CHECK(r.noise_z2 > 0);
  CHECK(r.shift_x == 1);
  SensorOptions mixed = kinect;
  mixed.noise_z2 = 0.01;
  CHECK_THROWS_WITH(mixed.resolved(), Catch::Contains("perturb.sensor.preset = kinect sets every sensor value"));
  // A generated-looking frame: two surfaces, a textured image; the preset removes some returns, deterministically.
  const int64_t W = 64, H = 48;
  PerturbOptions p;
  p.sensor = kinect;
  CHECK(p.any_depth());
  const auto z = step(W, H, 30) + torch::linspace(0, 2, H).unsqueeze(1);
  const auto image = torch::rand({3, H, W}, torch::Generator(at::detail::createCPUGenerator(3)));
  const auto K = K_of(50, W, H);
  const PerturbedDepth a = perturb_depth(z, torch::ones({H, W}), p, 4, image, K);
  const PerturbedDepth b = perturb_depth(z, torch::ones({H, W}), p, 4, image, K);
  const PerturbedDepth c = perturb_depth(z, torch::ones({H, W}), p, 5, image, K);
  CHECK(torch::equal(a.depth, b.depth));
  CHECK_FALSE(torch::equal(a.depth, c.depth));
  const double kept = a.valid.mean().item<double>();
  CHECK(kept < 0.97);
  CHECK(kept > 0.3);
  // The keys validate, and a sweep reaches them.
  nlohmann::json j = config_to_json(PerturbOptions{});
  j["sensor"]["grazing_deg"] = 120;
  CHECK_THROWS_WITH(config_from_json<PerturbOptions>(j, "perturb"), Catch::Contains("grazing_deg"));
  j["sensor"]["grazing_deg"] = 0;
  j["sensor"]["preset"] = "kinect2";
  CHECK_THROWS_WITH(config_from_json<PerturbOptions>(j, "perturb"), Catch::Contains("preset"));
  MethodOptions m = named_method("lift", "lift");
  m.sweep_key = "perturb.sensor.noise_z2";
  m.sweep_values = {0.0, 0.002};
  const auto swept = expand_sweeps({m});
  REQUIRE(swept.size() == 2);
  CHECK(swept[1].perturb.sensor.noise_z2 == 0.002);
  CHECK(swept[1].label() == "lift~noise_z20.002");
}

}  // namespace sensor_test
