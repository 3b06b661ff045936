// Image regions, detail ratio and Gaussian density for the evaluator's breakdown by region.
#include "metrics/regions.h"

#include <cmath>
#include <limits>

#include <torch/torch.h>

#include "core/error.h"

namespace isplat {

namespace {
namespace F = torch::nn::functional;

torch::Tensor grey(const torch::Tensor& image) {
  return image.to(torch::kFloat32).mean(0);
}  // [H,W]

// The median of `values` where `where` holds, or NaN when it holds nowhere.
double masked_median(const torch::Tensor& values, const torch::Tensor& where) {
  const auto v = values.masked_select(where);
  return v.numel() ? v.median().item<double>() : std::numeric_limits<double>::quiet_NaN();
}

// A 3x3 filter of a [H,W] image, valid positions only, padded back to [H,W] with zeros.
torch::Tensor filter3(const torch::Tensor& g, const std::vector<float>& taps) {
  const auto kernel = torch::tensor(taps).view({1, 1, 3, 3});
  return F::pad(F::conv2d(g.view({1, 1, g.size(0), g.size(1)}), kernel), F::PadFuncOptions({1, 1, 1, 1}))
      .view({g.size(0), g.size(1)});
}

// Pixels with a whole 3x3 neighbourhood inside the image.
torch::Tensor inner(int64_t H, int64_t W) {
  auto m = torch::zeros({H, W}, torch::kBool);
  if (H > 2 && W > 2) m.slice(0, 1, H - 1).slice(1, 1, W - 1).fill_(true);
  return m;
}
}  // namespace

std::vector<std::pair<std::string, torch::Tensor>> image_regions(const torch::Tensor& target,
                                                                 const torch::Tensor& ref_depth,
                                                                 const torch::Tensor& mask, int64_t edge_px,
                                                                 double edge_jump) {
  ISPLAT_CHECK(target.dim() == 3 && target.size(0) == 3, "regions: target must be [3,H,W], got ", target.sizes());
  const int64_t H = target.size(1), W = target.size(2);
  ISPLAT_CHECK(mask.dim() == 2 && mask.size(0) == H && mask.size(1) == W, "regions: mask must be [", H, ",", W,
               "], got ", mask.sizes());
  ISPLAT_CHECK(edge_px >= 0 && edge_jump > 0, "regions: edge_px ", edge_px, " and edge_jump ", edge_jump);
  const auto scored = mask > 0;
  std::vector<std::pair<std::string, torch::Tensor>> out;
  auto add = [&](const char* name, const torch::Tensor& m) { out.push_back({name, m.to(torch::kFloat32)}); };

  if (ref_depth.defined()) {
    ISPLAT_CHECK(ref_depth.dim() == 2 && ref_depth.size(0) == H && ref_depth.size(1) == W,
                 "regions: reference depth must be [", H, ",", W, "], got ", ref_depth.sizes());
    const auto z = ref_depth.to(torch::kFloat32);
    const auto valid = torch::isfinite(z) & (z > 0);
    const auto zv = torch::where(valid, z, torch::zeros_like(z));
    const double median = masked_median(zv, scored & valid);
    add("near", scored & valid & (zv <= median));
    add("far", scored & valid & (zv > median));
    // Depth edges between right and down neighbours, marked on both pixels of the pair.
    auto edge = torch::zeros({H, W}, torch::kBool);
    auto mark = [&](int64_t dim) {
      const int64_t n = zv.size(dim);
      const auto a = zv.narrow(dim, 0, n - 1), b = zv.narrow(dim, 1, n - 1);
      const auto va = valid.narrow(dim, 0, n - 1), vb = valid.narrow(dim, 1, n - 1);
      const auto jump = (va & vb & ((a - b).abs() >= edge_jump * torch::minimum(a, b))) | (va ^ vb);
      edge.narrow(dim, 0, n - 1) |= jump;
      edge.narrow(dim, 1, n - 1) |= jump;
    };
    if (H > 1) mark(0);
    if (W > 1) mark(1);
    const int64_t k = 2 * edge_px + 1;
    const auto band = F::max_pool2d(edge.to(torch::kFloat32).view({1, 1, H, W}),
                                    F::MaxPool2dFuncOptions(k).stride(1).padding(edge_px))
                          .view({H, W}) > 0;
    add("silhouette", scored & band);
    add("interior", scored & valid & ~band);
  }

  const auto g = grey(target);
  const auto dx = filter3(g, {0, 0, 0, -0.5f, 0, 0.5f, 0, 0, 0}), dy = filter3(g, {0, -0.5f, 0, 0, 0, 0, 0, 0.5f, 0});
  const auto energy = F::avg_pool2d((dx * dx + dy * dy).view({1, 1, H, W}),
                                    F::AvgPool2dFuncOptions(5).stride(1).padding(2).count_include_pad(false))
                          .view({H, W});
  const double median = masked_median(energy, scored);
  add("textured", scored & (energy > median));
  add("flat", scored & (energy <= median));
  return out;
}

double detail_ratio(const torch::Tensor& rendered, const torch::Tensor& target, const torch::Tensor& mask) {
  ISPLAT_CHECK(rendered.sizes() == target.sizes() && target.dim() == 3, "detail: rendered ", rendered.sizes(),
               " and target ", target.sizes(), " must both be [3,H,W]");
  const int64_t H = target.size(1), W = target.size(2);
  const auto where = ((mask > 0) & inner(H, W)).to(torch::kFloat32);
  const std::vector<float> laplacian = {0, 1, 0, 1, -4, 1, 0, 1, 0};
  const double r = (filter3(grey(rendered), laplacian).pow(2) * where).sum().item<double>();
  const double t = (filter3(grey(target), laplacian).pow(2) * where).sum().item<double>();
  if (!(where.sum().item<double>() > 0) || !(t > 0)) return std::numeric_limits<double>::quiet_NaN();
  return r / t;
}

double centre_density(const torch::Tensor& means, const Camera& camera, const torch::Tensor& mask) {
  ISPLAT_CHECK(camera.batch() == 0, "density: one camera, not a batch");
  ISPLAT_CHECK(mask.dim() == 2 && mask.size(0) == camera.height && mask.size(1) == camera.width,
               "density: mask must be [", camera.height, ",", camera.width, "], got ", mask.sizes());
  const double pixels = (mask > 0).sum().item<double>();
  if (!(pixels > 0)) return std::numeric_limits<double>::quiet_NaN();
  ISPLAT_CHECK(means.dim() == 2 && means.size(1) == 3, "density: means must be [N,3], got ", means.sizes());
  const auto p = transform_points(camera.T_cw.to(torch::kFloat32), means.to(torch::kFloat32));
  const auto front = p.select(1, 2) > 0;
  const auto uv = project_points(p.index({front}), camera.K.to(torch::kFloat32)).floor().to(torch::kLong);
  const auto u = uv.select(1, 0), v = uv.select(1, 1);
  const auto inside = (u >= 0) & (u < camera.width) & (v >= 0) & (v < camera.height);
  const auto index = (v * camera.width + u).masked_select(inside);
  const auto hits = (mask > 0).reshape({-1}).index({index});
  return hits.sum().item<double>() / pixels;
}

}  // namespace isplat
