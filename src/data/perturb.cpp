// Source-view perturbations with a seeded generator: noise, warp, holes and blur on depth, exposure and JPEG on the
// image; and the per-tuple draw of training's depth errors.
#include "data/perturb.h"

#include <ATen/CPUGeneratorImpl.h>
#include <torch/torch.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <limits>
#include <vector>

#include "core/config.h"
#include "core/error.h"
#include "geometry/color.h"
#include "geometry/pixel_mask.h"
#include "io/tensor_image.h"

namespace isplat {

bool PerturbOptions::any_depth() const {
  return depth_scale != 1.0 || depth_noise > 0 || depth_warp > 0 || depth_blur_px > 0 || depth_holes > 0 ||
         depth_edge_noise > 0 || depth_edge_holes > 0 || depth_side != "all" || sensor.any();
}

bool PerturbOptions::any() const {
  return any_depth() || exposure != 1.0 || jpeg_quality > 0;
}

void PerturbOptions::visit(ConfigVisitor& v) {
  v.field("depth_scale", depth_scale, "global scale error of the source depth (prior output): z x s",
          Range::above(0.0));
  v.field("depth_noise", depth_noise, "multiplicative depth noise sigma on every pixel, z(1 + eps)",
          Range::between(0.0, 1.0));
  v.field("depth_warp", depth_warp,
          "smooth shape error of the depth: z x exp(sigma f), f bilinear between N(0, 1) values on a coarse grid",
          Range::between(0.0, 2.0));
  v.field("depth_warp_cells", depth_warp_cells, "grid cells of depth_warp across the image width",
          Range::between(1, 64));
  v.field("depth_blur_px", depth_blur_px, "Gaussian blur sigma of the depth map in pixels", Range::between(0.0, 100.0));
  v.field("depth_holes", depth_holes, "share of valid depth pixels made invalid", Range::between(0.0, 0.99));
  v.field("depth_hole_size", depth_hole_size,
          "holes are blobs of about this radius in pixels (a smooth random field's highest values); 0 = "
          "independent pixels",
          Range::between(0.0, 100.0));
  v.field("depth_edge_noise", depth_edge_noise, "multiplicative depth noise sigma at depth edges only",
          Range::between(0.0, 1.0));
  v.field("depth_edge_holes", depth_edge_holes,
          "drop-outs at occlusion edges: depth within this many pixels (Chebyshev) of a depth edge (a 5% jump "
          "between neighbours, found before any other change) made invalid",
          Range::between(0, 64));
  v.field("depth_edge_holes_side", depth_edge_holes_side,
          "which side of each depth edge depth_edge_holes drops: both, or far (only pixels with a 5% nearer pixel "
          "within depth_edge_holes + 1: the shadow a stereo or time-of-flight sensor leaves behind an occluder)",
          {"both", "far"});
  v.field("depth_side", depth_side, "keep depth (and the prompts drawn from it) only on this side of the image",
          {"all", "left", "right", "top", "bottom"});
  v.field("exposure", exposure, "source image multiplied by this in linear light", Range::above(0.0));
  v.field("jpeg_quality", jpeg_quality, "re-encode the source image as JPEG at this quality (0 = off)",
          Range::between(0, 100));
  v.section("sensor",
            "a depth sensor's errors on the source depth, applied after depth_edge_holes and before the other depth "
            "options: drop-outs (range, grazing angles, dark surfaces, occlusion shadows), flying pixels, noise "
            "growing with z^2, disparity quantization, misregistration; a preset or single effects",
            sensor);
}

torch::Tensor depth_edges(const torch::Tensor& depth, const torch::Tensor& valid, double relative) {
  const auto z = depth.contiguous(), ok = valid.to(torch::kFloat32).contiguous();
  const int64_t H = z.size(0), W = z.size(1);
  auto out = torch::zeros({H, W});
  const float *pz = z.data_ptr<float>(), *pv = ok.data_ptr<float>();
  float* po = out.data_ptr<float>();
  for (int64_t i = 0; i < H; ++i)
    for (int64_t j = 0; j < W; ++j) {
      const int64_t p = i * W + j;
      if (pv[p] == 0) continue;
      for (const int64_t q : {j > 0 ? p - 1 : -1, j + 1 < W ? p + 1 : -1, i > 0 ? p - W : -1, i + 1 < H ? p + W : -1})
        if (q >= 0 && pv[q] != 0 && std::abs(pz[q] - pz[p]) > relative * pz[p]) po[p] = 1;
    }
  return out;
}

PerturbedDepth perturb_depth(const torch::Tensor& depth_in, const torch::Tensor& valid_in, const PerturbOptions& o,
                             uint64_t seed, const torch::Tensor& image, const torch::Tensor& K) {
  if (!o.any_depth()) return {depth_in, valid_in};
  auto gen = at::make_generator<at::CPUGeneratorImpl>(seed * 0x9E3779B97F4A7C15ull + 1);
  auto depth = depth_in.to(torch::kFloat32).clone();
  auto valid = (valid_in > 0).logical_and(depth > 0).logical_and(torch::isfinite(depth)).to(torch::kFloat32);
  depth = torch::nan_to_num(depth, 0.0, 0.0, 0.0);
  const int64_t H = depth.size(0), W = depth.size(1);
  depth = depth * valid;
  if (o.depth_edge_holes > 0) {  // before anything moves the edges: a band on both sides of every depth edge
    const auto edges = depth_edges(depth, valid).to(torch::kUInt8).contiguous();
    const std::vector<uint8_t> mask(edges.data_ptr<uint8_t>(), edges.data_ptr<uint8_t>() + H * W);
    std::vector<uint8_t> band = dilate_square(mask, H, W, o.depth_edge_holes);
    if (o.depth_edge_holes_side == "far") {  // only band pixels with one 5% nearer within n + 1: the far side
      const auto far = far_edge_band(depth, valid, o.depth_edge_holes).to(torch::kUInt8).contiguous();
      const uint8_t* fp = far.data_ptr<uint8_t>();
      for (int64_t p = 0; p < H * W; ++p) band[p] = band[p] && fp[p];
    }
    const auto drop = torch::from_blob(const_cast<uint8_t*>(band.data()), {H, W}, torch::kUInt8);
    valid = valid * (drop == 0).to(torch::kFloat32);
    depth = depth * valid;
  }
  if (o.sensor.any()) {
    const SensorDepth sensed = apply_sensor(depth, valid, o.sensor, seed, image, K);
    depth = sensed.depth.clone(), valid = sensed.valid.clone();
  }
  if (o.depth_blur_px > 0) {  // normalized convolution: blur depth·valid and valid, then divide
    cv::Mat d(static_cast<int>(H), static_cast<int>(W), CV_32F, depth.data_ptr<float>());
    auto vc = valid.contiguous();
    cv::Mat m(static_cast<int>(H), static_cast<int>(W), CV_32F, vc.data_ptr<float>());
    cv::Mat bd, bm;
    cv::GaussianBlur(d, bd, cv::Size(0, 0), o.depth_blur_px, o.depth_blur_px, cv::BORDER_REFLECT);
    cv::GaussianBlur(m, bm, cv::Size(0, 0), o.depth_blur_px, o.depth_blur_px, cv::BORDER_REFLECT);
    cv::Mat blurred = bd / cv::max(bm, 1e-6f);
    depth = torch::from_blob(blurred.data, {H, W}, torch::kFloat32).clone() * valid;
  }
  if (o.depth_edge_noise > 0) {
    const auto edges = depth_edges(depth, valid);
    depth = depth * (1.0 + o.depth_edge_noise * torch::randn({H, W}, gen) * edges);
  }
  if (o.depth_noise > 0) depth = depth * (1.0 + o.depth_noise * torch::randn({H, W}, gen));
  if (o.depth_warp > 0) {  // unit-variance values on a coarse grid, bilinear in between, as a log-depth offset
    const int64_t gw = o.depth_warp_cells + 1;
    const int64_t gh = std::max<int64_t>(2, std::llround(static_cast<double>(o.depth_warp_cells) * H / W) + 1);
    const auto nodes = torch::randn({1, 1, gh, gw}, gen);
    const auto field = torch::nn::functional::interpolate(nodes, torch::nn::functional::InterpolateFuncOptions()
                                                                     .size(std::vector<int64_t>{H, W})
                                                                     .mode(torch::kBilinear)
                                                                     .align_corners(true));
    depth = depth * torch::exp(o.depth_warp * field.view({H, W}));
  }
  depth = depth * o.depth_scale;
  if (o.depth_holes > 0) {  // exactly round(share · valid) of the valid pixels
    const auto idx = torch::nonzero(valid.view({-1}) > 0).view({-1});
    const int64_t k = std::llround(o.depth_holes * static_cast<double>(idx.numel()));
    torch::Tensor drop;
    if (o.depth_hole_size > 0) {  // blobs: the k valid pixels where a smooth random field is highest
      auto field = torch::randn({H, W}, gen).contiguous();
      cv::Mat f(static_cast<int>(H), static_cast<int>(W), CV_32F, field.data_ptr<float>()), smooth;
      cv::GaussianBlur(f, smooth, cv::Size(0, 0), o.depth_hole_size, o.depth_hole_size, cv::BORDER_REFLECT);
      const auto at_valid = torch::from_blob(smooth.data, {H * W}, torch::kFloat32).index({idx});
      drop = idx.index({std::get<1>(at_valid.topk(k))});
    } else {  // independent pixels, chosen by a seeded permutation
      drop = idx.index({torch::randperm(idx.numel(), gen, torch::kLong).narrow(0, 0, k)});
    }
    valid.view({-1}).index_fill_(0, drop, 0.0);
  }
  if (o.depth_side != "all") {
    auto keep = torch::zeros({H, W});
    if (o.depth_side == "left") keep.narrow(1, 0, W / 2).fill_(1);
    if (o.depth_side == "right") keep.narrow(1, W / 2, W - W / 2).fill_(1);
    if (o.depth_side == "top") keep.narrow(0, 0, H / 2).fill_(1);
    if (o.depth_side == "bottom") keep.narrow(0, H / 2, H - H / 2).fill_(1);
    valid = valid * keep;
  }
  valid = valid * (depth > 0).to(torch::kFloat32);  // noise can never leave a negative depth behind
  return {(depth * valid).contiguous(), valid.contiguous()};
}

torch::Tensor perturb_prompts(const torch::Tensor& prompts, const PerturbOptions& o, uint64_t seed, int64_t width,
                              int64_t height) {
  if (!prompts.defined() || prompts.numel() == 0 || !o.any_depth()) return prompts;
  ISPLAT_CHECK(prompts.dim() == 2 && prompts.size(1) == 3, "perturb: prompts must be [P,3] (u, v, z), got ",
               prompts.sizes());
  auto gen = at::make_generator<at::CPUGeneratorImpl>(seed * 0x9E3779B97F4A7C15ull + 2);
  auto p = prompts.to(torch::kFloat32).clone();
  auto z = p.select(1, 2);
  if (o.depth_noise > 0) z.mul_(1.0 + o.depth_noise * torch::randn({p.size(0)}, gen));
  z.mul_(o.depth_scale);
  auto keep = z > 0;
  const auto u = p.select(1, 0), v = p.select(1, 1);
  if (o.depth_side == "left") keep = keep.logical_and(u < width / 2.0);
  if (o.depth_side == "right") keep = keep.logical_and(u >= width / 2.0);
  if (o.depth_side == "top") keep = keep.logical_and(v < height / 2.0);
  if (o.depth_side == "bottom") keep = keep.logical_and(v >= height / 2.0);
  if (o.depth_holes > 0) {
    const auto idx = torch::nonzero(keep).view({-1});
    const int64_t k = std::llround(o.depth_holes * static_cast<double>(idx.numel()));
    keep.index_fill_(0, idx.index({torch::randperm(idx.numel(), gen, torch::kLong).narrow(0, 0, k)}), false);
  }
  const auto out = p.index({keep}).contiguous();
  ISPLAT_CHECK(out.size(0) >= 3, "perturb: only ", out.size(0), " of ", prompts.size(0),
               " prompts are left after depth_side = ", o.depth_side, " and depth_holes = ", o.depth_holes,
               " (the sparse prior needs at least 3)");
  return out;
}

ViewTensors perturb_source(const ViewTensors& source, const PerturbOptions& o, uint64_t seed) {
  ViewTensors v = source;
  if (!o.any()) return v;
  if (o.any_depth() && source.depth.defined()) {
    PerturbedDepth d = perturb_depth(source.depth, source.valid, o, seed, source.image, source.camera.K);
    v.depth = d.depth, v.valid = d.valid, v.true_depth = source.depth;
  }
  if (o.exposure != 1.0)
    v.image = torch::clamp(linear_to_srgb(srgb_to_linear(source.image) * o.exposure), 0.0, 1.0).contiguous();
  if (o.jpeg_quality > 0) {
    cv::Mat rgb8, bgr8, back;
    tensor_to_image(v.image).convertTo(rgb8, CV_8UC3, 255.0);
    cv::cvtColor(rgb8, bgr8, cv::COLOR_RGB2BGR);
    std::vector<uchar> bytes;
    cv::imencode(".jpg", bgr8, bytes, {cv::IMWRITE_JPEG_QUALITY, static_cast<int>(o.jpeg_quality)});
    cv::cvtColor(cv::imdecode(bytes, cv::IMREAD_COLOR), rgb8, cv::COLOR_BGR2RGB);
    rgb8.convertTo(back, CV_32FC3, 1.0 / 255.0);
    v.image = image_to_tensor(back).contiguous();
  }
  return v;
}

}  // namespace isplat
