// Sensor-realistic depth: drop-outs (range, grazing angles, dark surfaces, occlusion shadows), flying pixels, noise
// growing with z^2, disparity quantization and misregistration, applied in the order a sensor makes them.
#include "data/sensor.h"

#include <ATen/CPUGeneratorImpl.h>
#include <torch/torch.h>

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <limits>
#include <vector>

#include "core/config.h"
#include "core/error.h"
#include "data/perturb.h"
#include "geometry/color.h"
#include "geometry/pixel_mask.h"

namespace isplat {

bool SensorOptions::any() const {
  const SensorOptions o = resolved();
  return o.max_range > 0 || o.grazing_deg > 0 || o.dark > 0 || o.shadow_px > 0 || o.flying > 0 || o.noise_z2 > 0 ||
         o.disparity_step > 0 || o.shift_x != 0 || o.shift_y != 0;
}

SensorOptions SensorOptions::resolved() const {
  if (preset == "none") return *this;
  SensorOptions plain = *this;
  plain.preset = "none";
  ISPLAT_CHECK(!plain.any(), "perturb.sensor.preset = ", preset,
               " sets every sensor value itself; leave the other perturb.sensor keys at their defaults, or use preset "
               "none with the values you want");
  SensorOptions o;
  if (preset == "kinect") {
    // A structured-light camera of the Kinect v1 class at its working range (Khoshelham and Elberink 2012: random
    // error about 1.4 mm x z^2, disparity steps of 1/8 px at f 580 px and a 7.5 cm baseline, i.e. 0.0029 / m).
    o.max_range = 5.0;
    o.grazing_deg = 75.0;
    o.dark = 0.01;
    o.shadow_px = 2;
    o.flying = 0.5;
    o.noise_z2 = 0.0014;
    o.disparity_step = 0.0029;
    o.shift_x = 1;
    o.shift_y = 1;
  } else {
    fail("perturb.sensor.preset: unknown preset '", preset, "' (none | kinect)");
  }
  return o;
}

void SensorOptions::visit(ConfigVisitor& v) {
  v.field("preset", preset,
          "a realistic combination: kinect = max_range 5, grazing_deg 75, dark 0.01, shadow_px 2, flying 0.5, "
          "noise_z2 0.0014, disparity_step 0.0029, shift_x 1, shift_y 1 (the other sensor keys must then stay at "
          "their defaults); none = only the keys given",
          {"none", "kinect"});
  v.field("max_range", max_range, "no depth return beyond this many metres (0 = off)", Range::between(0.0, 1e4));
  v.field("grazing_deg", grazing_deg,
          "no return where the angle between the pixel's ray and the surface normal (from the depth) exceeds this "
          "many degrees (0 = off)",
          Range::between(0.0, 90.0));
  v.field("dark", dark,
          "no return where the source image's linear luminance is below this (dark, absorbing surfaces; 0 = off). "
          "Specular surfaces are not modelled: the datasets carry no material information",
          Range::between(0.0, 1.0));
  v.field("shadow_px", shadow_px,
          "no return within this many pixels on the far side of an occlusion edge (a 5% depth jump): the shadow a "
          "structured-light or time-of-flight sensor leaves behind an occluder (0 = off)",
          Range::between(0, 64));
  v.field("flying", flying,
          "share of the pixels at depth edges given a depth drawn between the nearest and farthest surface around "
          "them (flying pixels; 0 = off)",
          Range::unit());
  v.field("noise_z2", noise_z2, "depth noise whose sigma grows with depth squared: sigma = noise_z2 * z^2 metres",
          Range::between(0.0, 1.0));
  v.field("disparity_step", disparity_step,
          "quantization in disparity: 1/z snapped to multiples of this (1/m), so depth steps grow as step * z^2 "
          "(0 = off)",
          Range::between(0.0, 1.0));
  v.field("shift_x", shift_x, "misregistration: the depth map moved this many pixels right of the colour image",
          Range::between(-8, 8));
  v.field("shift_y", shift_y, "misregistration: the depth map moved this many pixels down from the colour image",
          Range::between(-8, 8));
}

torch::Tensor far_edge_band(const torch::Tensor& depth, const torch::Tensor& valid, int64_t radius) {
  const int64_t H = depth.size(0), W = depth.size(1);
  const auto z = depth.to(torch::kFloat32).contiguous();
  const auto ok = (valid > 0).contiguous();
  const auto edges = depth_edges(z, ok).to(torch::kUInt8).contiguous();
  const std::vector<uint8_t> mask(edges.data_ptr<uint8_t>(), edges.data_ptr<uint8_t>() + H * W);
  std::vector<uint8_t> band = dilate_square(mask, H, W, radius);
  // The smallest valid depth within radius + 1 px (Chebyshev): an erosion with invalid pixels (and the outside of the
  // image) at +inf.
  const float inf = std::numeric_limits<float>::infinity();
  auto zi = torch::where(ok, z, torch::full_like(z, inf)).contiguous();
  const int k = static_cast<int>(2 * (radius + 1) + 1);
  cv::Mat zm(static_cast<int>(H), static_cast<int>(W), CV_32F, zi.data_ptr<float>()), nearest;
  cv::erode(zm, nearest, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(k, k)), cv::Point(-1, -1), 1,
            cv::BORDER_CONSTANT, cv::Scalar::all(inf));
  const float* zp = z.data_ptr<float>();
  const float* np = nearest.ptr<float>();
  const bool* vp = ok.data_ptr<bool>();
  auto out = torch::zeros({H, W}, torch::kBool);
  bool* op = out.data_ptr<bool>();
  for (int64_t p = 0; p < H * W; ++p) op[p] = vp[p] && band[p] && np[p] < 0.95f * zp[p];
  return out;
}

torch::Tensor incidence_deg(const torch::Tensor& depth, const torch::Tensor& valid, const torch::Tensor& K) {
  ISPLAT_CHECK(K.defined() && K.numel() == 9, "perturb.sensor.grazing_deg needs the source camera's intrinsics K");
  const int64_t H = depth.size(0), W = depth.size(1);
  const auto z = depth.to(torch::kFloat64).contiguous();
  const auto ok = (valid > 0).logical_and(z > 0).contiguous();
  const auto k = K.to(torch::kFloat64).contiguous();
  const double *kp = k.data_ptr<double>(), fx = kp[0], skew = kp[1], cx = kp[2], fy = kp[4], cy = kp[5];
  const double* zp = z.data_ptr<double>();
  const bool* vp = ok.data_ptr<bool>();
  auto point = [&](int64_t i, int64_t j) {  // back-projection of the pixel centre
    const double y = (i + 0.5 - cy) / fy, x = (j + 0.5 - cx - skew * y) / fx, d = zp[i * W + j];
    return std::array<double, 3>{x * d, y * d, d};
  };
  // Neighbours on the same surface: both sides valid with a small second difference (a surface seen at a grazing
  // angle jumps by far more than 5% between pixels, but steadily), else the one side within 5% in depth.
  auto near = [&](int64_t p, int64_t q) { return vp[q] && std::abs(zp[q] - zp[p]) <= 0.05 * zp[p]; };
  auto linear = [&](int64_t p, int64_t a, int64_t b) {
    return vp[a] && vp[b] && std::abs(zp[a] + zp[b] - 2 * zp[p]) <= 0.05 * zp[p];
  };
  auto out = torch::full({H, W}, std::numeric_limits<double>::quiet_NaN(), torch::kFloat64);
  double* op = out.data_ptr<double>();
  for (int64_t i = 0; i < H; ++i)
    for (int64_t j = 0; j < W; ++j) {
      const int64_t p = i * W + j;
      if (!vp[p]) continue;
      // The tangent along x and y: central where the surface runs on through the pixel, else one-sided.
      const bool cx2 = j > 0 && j + 1 < W && linear(p, p - 1, p + 1);
      const bool cy2 = i > 0 && i + 1 < H && linear(p, p - W, p + W);
      const bool l = cx2 || (j > 0 && near(p, p - 1)), r = cx2 || (j + 1 < W && near(p, p + 1));
      const bool u = cy2 || (i > 0 && near(p, p - W)), d = cy2 || (i + 1 < H && near(p, p + W));
      if (!(l || r) || !(u || d)) continue;
      const auto a = point(i, r ? j + 1 : j), b = point(i, l ? j - 1 : j);
      const auto c = point(d ? i + 1 : i, j), e = point(u ? i - 1 : i, j);
      const double tx[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]}, ty[3] = {c[0] - e[0], c[1] - e[1], c[2] - e[2]};
      const double n[3] = {tx[1] * ty[2] - tx[2] * ty[1], tx[2] * ty[0] - tx[0] * ty[2], tx[0] * ty[1] - tx[1] * ty[0]};
      const auto P = point(i, j);
      const double nn = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      const double pn = std::sqrt(P[0] * P[0] + P[1] * P[1] + P[2] * P[2]);
      if (nn == 0 || pn == 0) continue;
      const double cosang = std::abs(n[0] * P[0] + n[1] * P[1] + n[2] * P[2]) / (nn * pn);
      op[p] = std::acos(std::min(1.0, cosang)) * 180.0 / M_PI;
    }
  return out;
}

SensorDepth apply_sensor(const torch::Tensor& depth_in, const torch::Tensor& valid_in, const SensorOptions& options,
                         uint64_t seed, const torch::Tensor& image, const torch::Tensor& K) {
  const SensorOptions o = options.resolved();
  auto gen = at::make_generator<at::CPUGeneratorImpl>(seed * 0x9E3779B97F4A7C15ull + 3);
  auto depth = torch::nan_to_num(depth_in.to(torch::kFloat32), 0.0, 0.0, 0.0).contiguous();
  auto valid = (valid_in > 0).logical_and(depth > 0);
  const int64_t H = depth.size(0), W = depth.size(1);
  // Drop-outs, all decided on the true depth.
  auto keep = valid.clone();
  if (o.max_range > 0) keep &= depth <= o.max_range;
  if (o.grazing_deg > 0) {
    const auto angle = incidence_deg(depth, valid, K);
    keep &= angle.le(o.grazing_deg).logical_or(torch::isnan(angle));  // no normal estimate: kept
  }
  if (o.dark > 0) {
    ISPLAT_CHECK(image.defined() && image.dim() == 3 && image.size(1) == H && image.size(2) == W,
                 "perturb.sensor.dark needs the source image at the depth's size ", H, "x", W);
    const auto lin = srgb_to_linear(image.to(torch::kFloat32));
    const auto lum = 0.2126 * lin[0] + 0.7152 * lin[1] + 0.0722 * lin[2];
    keep &= lum >= o.dark;
  }
  if (o.shadow_px > 0) keep &= far_edge_band(depth, valid, o.shadow_px).logical_not();
  // Flying pixels: edge pixels take a depth between the nearest and farthest surface in their 3x3 neighbourhood.
  if (o.flying > 0) {
    const auto edges = depth_edges(depth, valid.to(torch::kFloat32)) > 0;
    const auto inf = torch::full_like(depth, std::numeric_limits<float>::infinity());
    const auto zlo = torch::where(valid, depth, inf).view({1, 1, H, W});
    const auto zhi = torch::where(valid, depth, torch::zeros_like(depth)).view({1, 1, H, W});
    namespace F = torch::nn::functional;
    const auto pool = F::MaxPool2dFuncOptions(3).stride(1).padding(1);
    const auto near = (-F::max_pool2d(-zlo, pool)).view({H, W}), far = F::max_pool2d(zhi, pool).view({H, W});
    const auto draw = torch::rand({H, W}, gen), t = torch::rand({H, W}, gen);
    const auto fly = edges.logical_and(draw < o.flying);
    depth = torch::where(fly, near + t * (far - near), depth);
  }
  if (o.noise_z2 > 0) depth = depth + o.noise_z2 * depth * depth * torch::randn({H, W}, gen);
  if (o.disparity_step > 0) {
    const auto level = torch::round(1.0 / depth.clamp_min(1e-6) / o.disparity_step);
    keep &= level > 0;  // beyond the last disparity step: no return
    depth = 1.0 / (level.clamp_min(1) * o.disparity_step);
  }
  keep &= depth > 0;
  depth = torch::where(keep, depth, torch::zeros_like(depth));
  auto v = keep.to(torch::kFloat32);
  if (o.shift_x != 0 || o.shift_y != 0) {  // out(i, j) = in(i - shift_y, j - shift_x); uncovered pixels invalid
    auto moved = torch::zeros_like(depth), mv = torch::zeros_like(v);
    const int64_t sx = o.shift_x, sy = o.shift_y;
    const int64_t w = W - std::abs(sx), h = H - std::abs(sy);
    if (w > 0 && h > 0) {
      const int64_t src_i = std::max<int64_t>(0, -sy), src_j = std::max<int64_t>(0, -sx);
      const int64_t dst_i = std::max<int64_t>(0, sy), dst_j = std::max<int64_t>(0, sx);
      moved.narrow(0, dst_i, h).narrow(1, dst_j, w).copy_(depth.narrow(0, src_i, h).narrow(1, src_j, w));
      mv.narrow(0, dst_i, h).narrow(1, dst_j, w).copy_(v.narrow(0, src_i, h).narrow(1, src_j, w));
    }
    depth = moved, v = mv;
  }
  return {(depth * v).contiguous(), v.contiguous()};
}

}  // namespace isplat
