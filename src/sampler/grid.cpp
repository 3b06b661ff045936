// The triangle grid of a depth map and the support writers the sampling strategies share.
#include "sampler/grid.h"

#include <torch/torch.h>

#include <cmath>

#include "core/error.h"
#include "geometry/bilinear.h"
#include "geometry/camera_torch.h"

namespace isplat {

double discontinuity_threshold(double z_mean) {
  const double t = std::clamp(std::log10(std::max(z_mean, 1e-12)) / 2.0, 0.0, 1.0);
  return 1.05 + 0.05 * t;
}

bool depths_apart(double a, double b) {
  return std::max(a, b) / std::min(a, b) >= discontinuity_threshold(0.5 * (a + b));
}

namespace sampling {

Grid make_grid(const torch::Tensor& depth, const torch::Tensor& valid, const torch::Tensor& K,
               const torch::Tensor& image, torch::Tensor& d_keep, torch::Tensor& v_keep, torch::Tensor& i_keep) {
  ISPLAT_CHECK(depth.dim() == 2, "sampler: depth must be [H, W], got ", depth.sizes());
  ISPLAT_CHECK(valid.sizes() == depth.sizes(), "sampler: valid ", valid.sizes(), " differs from depth ", depth.sizes());
  ISPLAT_CHECK(
      image.dim() == 3 && image.size(0) == 3 && image.size(1) == depth.size(0) && image.size(2) == depth.size(1),
      "sampler: image must be [3, H, W] matching depth ", depth.sizes(), ", got ", image.sizes());
  ISPLAT_CHECK(K.sizes() == torch::IntArrayRef({3, 3}), "sampler: K must be [3, 3], got ", K.sizes());
  d_keep = depth.detach().to(torch::kFloat32).contiguous();
  v_keep = usable_depth(d_keep, valid.detach()).to(torch::kFloat32).contiguous();
  i_keep = image.detach().to(torch::kFloat32).contiguous();
  auto Kd = K.detach().to(torch::kFloat64).contiguous();
  const double* k = Kd.data_ptr<double>();
  return {d_keep.data_ptr<float>(),
          v_keep.data_ptr<float>(),
          i_keep.data_ptr<float>(),
          depth.size(0),
          depth.size(1),
          k[0],
          k[4],
          k[2],
          k[5],
          k[1]};
}

bool triangle_cross(const Grid& g, int64_t i, int64_t j, int t, double* cross) {
  int64_t r[3], c[3];
  triangle_pixels(i, j, t, r, c);
  double z[3], P[3][3];
  for (int k = 0; k < 3; ++k) {
    const int64_t idx = r[k] * g.W + c[k];
    if (g.valid[idx] == 0.0f) return false;
    z[k] = g.depth[idx];
    backproject(g, c[k] + 0.5, r[k] + 0.5, z[k], P[k]);
  }
  const double zmin = std::min({z[0], z[1], z[2]}), zmax = std::max({z[0], z[1], z[2]});
  if (zmax / zmin >= discontinuity_threshold((z[0] + z[1] + z[2]) / 3.0)) return false;
  double e1[3], e2[3];
  for (int k = 0; k < 3; ++k) e1[k] = P[1][k] - P[0][k], e2[k] = P[2][k] - P[0][k];
  cross[0] = e1[1] * e2[2] - e1[2] * e2[1];
  cross[1] = e1[2] * e2[0] - e1[0] * e2[2];
  cross[2] = e1[0] * e2[1] - e1[1] * e2[0];
  return true;
}

double triangle_area(const Grid& g, int64_t i, int64_t j, int t) {
  double cr[3];
  if (!triangle_cross(g, i, j, t, cr)) return 0.0;
  return 0.5 * std::sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]);
}

void write_support(const Grid& g, const Output& o, int64_t k, double u, double v, float z, float area) {
  o.uv[2 * k] = static_cast<float>(u);
  o.uv[2 * k + 1] = static_cast<float>(v);
  o.depth[k] = z;
  for (int c = 0; c < 3; ++c) o.color[3 * k + c] = bilinear_at(g.image + c * g.H * g.W, g.H, g.W, u, v);
  o.area[k] = area;
}

std::vector<float> triangle_areas(const Grid& g) {
  const int64_t Hq = g.H - 1, Wq = g.W - 1;
  ISPLAT_CHECK(Hq > 0 && Wq > 0, "sampler: depth map ", g.H, "x", g.W, " is too small to form triangles");
  std::vector<float> area(static_cast<size_t>(Hq * Wq * 2));
  for_each_row(Hq, [&](int64_t i) {
    for (int64_t j = 0; j < Wq; ++j)
      for (int t = 0; t < 2; ++t) area[(i * Wq + j) * 2 + t] = static_cast<float>(triangle_area(g, i, j, t));
  });
  return area;
}

float pixel_area(const Grid& g, int64_t i, int64_t j) {
  if (i + 1 < g.H && j + 1 < g.W) {
    const double a = triangle_area(g, i, j, 0) + triangle_area(g, i, j, 1);
    if (a > 0) return static_cast<float>(a);
  }
  const double z = g.depth[i * g.W + j];
  return static_cast<float>(z * z / (g.fx * g.fy));
}

Supports allocate(int64_t n) {
  Supports s;
  s.uv = torch::empty({n, 2});
  s.depth = torch::empty({n});
  s.color = torch::empty({n, 3});
  s.area = torch::empty({n});
  return s;
}

Output pointers(Supports& s) {
  return {s.uv.data_ptr<float>(), s.depth.data_ptr<float>(), s.color.data_ptr<float>(), s.area.data_ptr<float>()};
}

void rescale_areas(Supports& s, double total, int64_t count) {
  torch::Tensor a = count < 0 ? s.area : s.area.narrow(0, 0, count);
  const double sum = a.sum().item<double>();
  if (sum > 0) a.mul_(total / sum);
}

void write_pixel_supports(const Grid& g, const Output& o, const std::vector<int64_t>& pixels, int64_t count) {
  at::parallel_for(0, count, 4096, [&](int64_t b, int64_t e) {
    for (int64_t k = b; k < e; ++k) {
      const int64_t p = pixels[k], i = p / g.W, j = p % g.W;
      write_support(g, o, k, j + 0.5, i + 0.5, g.depth[p], pixel_area(g, i, j));
    }
  });
}

std::vector<int64_t> spread(const std::vector<int64_t>& pixels, int64_t count) {
  const int64_t size = static_cast<int64_t>(pixels.size());
  if (count >= size) return pixels;
  std::vector<int64_t> out(static_cast<size_t>(count));
  for (int64_t k = 0; k < count; ++k) out[k] = pixels[static_cast<size_t>(k * size / count)];
  return out;
}

}  // namespace sampling
}  // namespace isplat
