// PLY: write -> read round trip, a fixture in the exact 3DGS header order, extra properties, bad files.
#include <catch2/catch.hpp>

#include <torch/torch.h>

#include "core/error.h"
#include "decoder/composer.h"
#include "io/ply.h"
#include "support/test_util.h"

using namespace isplat;

TEST_CASE("ply: write then read returns the same Gaussians", "[ply]") {
  torch::manual_seed(0);
  const int64_t N = 50;
  Gaussians g{torch::randn({N, 3}), torch::rand({N, 3}) * 0.1 + 1e-3, torch::randn({N, 4}),
              torch::rand({N, 3}) * 0.9 + 0.05, torch::rand({N}) * 0.9 + 0.05};
  const auto dir = test::temp_dir("ply");
  write_ply(dir + "/s.ply", g, true);
  const Gaussians b = read_ply(dir + "/s.ply", true);
  CHECK(torch::allclose(b.means, g.means));
  CHECK(torch::allclose(b.scales, g.scales, 1e-5, 1e-8));
  CHECK(torch::allclose(b.opacities, g.opacities, 1e-5, 1e-6));
  CHECK(torch::allclose(b.colors, g.colors, 1e-4, 1e-5));
  CHECK(torch::allclose(b.quats, g.quats / g.quats.norm(2, 1, true), 1e-5, 1e-6));
  const std::string bytes = test::read_bytes(dir + "/s.ply");
  CHECK(bytes.size() == bytes.find("end_header\n") + 11 + N * 17 * 4);
}

TEST_CASE("ply: a fixture in the exact 3DGS header order, with extra properties, reads correctly", "[ply]") {
  // Two vertices, in the order 3DGS writes (including f_rest_0 that we skip).
  std::string h = "ply\nformat binary_little_endian 1.0\nelement vertex 2\n";
  const char* names[] = {"x",        "y",       "z",       "nx",      "ny",      "nz",    "f_dc_0", "f_dc_1", "f_dc_2",
                         "f_rest_0", "opacity", "scale_0", "scale_1", "scale_2", "rot_0", "rot_1",  "rot_2",  "rot_3"};
  for (const char* n : names) h += std::string("property float ") + n + "\n";
  h += "end_header\n";
  std::vector<float> v = {1,
                          2,
                          3,
                          0,
                          0,
                          1,
                          0,
                          0,
                          0,
                          9,
                          0,
                          -2,
                          -3,
                          -4,
                          1,
                          0,
                          0,
                          0,
                          -1,
                          0,
                          5,
                          0,
                          0,
                          0,
                          float(0.5 / kShC0),
                          float(-0.5 / kShC0),
                          0,
                          9,
                          2,
                          0,
                          0,
                          0,
                          0,
                          0,
                          1,
                          0};
  const auto dir = test::temp_dir("ply_fixture");
  test::write_bytes(dir + "/f.ply", h + std::string(reinterpret_cast<const char*>(v.data()), v.size() * 4));
  const Gaussians g = read_ply(dir + "/f.ply", false);
  REQUIRE(g.count() == 2);
  CHECK(g.means[0][2].item<float>() == 3.0f);
  CHECK(g.opacities[0].item<float>() == Approx(0.5f));
  CHECK(g.scales[0][1].item<float>() == Approx(std::exp(-3.0f)));
  CHECK(g.colors[0][0].item<float>() == Approx(0.5f));
  CHECK(g.colors[1][0].item<float>() == Approx(1.0f));
  CHECK(g.colors[1][1].item<float>() == Approx(0.0f).margin(1e-6));
  CHECK(g.opacities[1].item<float>() == Approx(1.0f / (1.0f + std::exp(-2.0f))));
  CHECK(g.quats[1][2].item<float>() == 1.0f);

  test::write_bytes(dir + "/t.ply", h + std::string(reinterpret_cast<const char*>(v.data()), 30));
  CHECK_THROWS_WITH(read_ply(dir + "/t.ply"), Catch::Contains("t.ply: truncated"));
  test::write_bytes(dir + "/a.ply", "ply\nformat ascii 1.0\nelement vertex 0\nend_header\n");
  CHECK_THROWS_WITH(read_ply(dir + "/a.ply"), Catch::Contains("format 'ascii' is not supported"));
  std::string missing = h;
  missing.replace(missing.find("property float opacity\n"), 23, "");
  test::write_bytes(dir + "/m.ply", missing + std::string(reinterpret_cast<const char*>(v.data()), v.size() * 4));
  CHECK_THROWS_WITH(read_ply(dir + "/m.ply"), Catch::Contains("missing property 'opacity'"));
  CHECK_THROWS_WITH(read_ply(dir + "/none.ply"), Catch::Contains("none.ply: no such file"));
}
