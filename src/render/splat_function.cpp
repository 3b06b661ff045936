// The autograd Function around the render kernels, plus input validation, batching and RenderOptions' config keys.
#include <torch/torch.h>

#include <algorithm>
#include <cmath>

#include "core/config.h"
#include "core/error.h"
#include "render/kernels.h"
#include "render/render.h"

namespace isplat {

void RenderOptions::visit(ConfigVisitor& v) {
  v.field("background", background, "background colour (3 numbers, linear RGB) seen where the splats are transparent");
  v.field("antialiased", antialiased, "compensate opacity for the dilation (Mip-Splatting / gsplat antialiased mode)");
  v.field("near", near, "near plane in metres: Gaussians closer than this are culled", Range::above(0.0));
  v.field("dilation", dilation, "screen-space low-pass filter in px², added to each 2D covariance",
          Range::at_least(0.0));
  v.field("depth", depth,
          "rendered depth: center (each Gaussian's mean depth, differentiable) or plane (where the pixel's ray meets "
          "the Gaussian's flattest plane: smooth on slanted surfaces, no gradient)",
          {"center", "plane"});
}

namespace splat {
namespace {

using torch::Tensor;
using torch::autograd::AutogradContext;
using torch::autograd::variable_list;

void check_no_nonfinite(int64_t bad, const char* name) {
  ISPLAT_CHECK(bad == 0, "render: ", name, " has ", bad, " non-finite value", bad == 1 ? "" : "s");
}

}  // namespace

CameraParams camera_params(const torch::Tensor& K_in, const torch::Tensor& T_in, int64_t width, int64_t height,
                           bool validate) {
  const auto K = K_in.detach().to(torch::kFloat64).contiguous();
  const auto T = T_in.detach().to(torch::kFloat64).contiguous();
  const double* k = K.data_ptr<double>();
  const double* t = T.data_ptr<double>();
  if (validate) {
    check_no_nonfinite(std::count_if(k, k + 9, [](double x) { return !std::isfinite(x); }), "camera K");
    check_no_nonfinite(std::count_if(t, t + 16, [](double x) { return !std::isfinite(x); }), "camera T_cw");
    ISPLAT_CHECK(k[0] > 0 && k[4] > 0, "render: camera focal lengths must be positive, got fx=", k[0], " fy=", k[4]);
    ISPLAT_CHECK(k[3] == 0 && k[6] == 0 && k[7] == 0 && k[8] == 1,
                 "render: camera K must be [[fx, s, cx], [0, fy, cy], [0, 0, 1]]");
  }
  CameraParams cam;
  cam.fx = k[0], cam.skew = k[1], cam.cx = k[2], cam.fy = k[4], cam.cy = k[5];
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) cam.R[3 * r + c] = t[4 * r + c];
    cam.t[r] = t[4 * r + 3];
  }
  cam.width = width, cam.height = height;
  return cam;
}

namespace {

struct Settings {
  ProjectSettings project;
  double background[3];
};

Settings settings_from(AutogradContext* ctx) {
  Settings s;
  s.project.near = ctx->saved_data["near"].toDouble();
  s.project.dilation = ctx->saved_data["dilation"].toDouble();
  s.project.antialiased = ctx->saved_data["antialiased"].toBool();
  const auto bg = ctx->saved_data["background"].toDoubleVector();
  for (int c = 0; c < 3; ++c) s.background[c] = bg[c];
  return s;
}

struct SplatFunction : torch::autograd::Function<SplatFunction> {
  static variable_list forward(AutogradContext* ctx, const Tensor& means, const Tensor& scales, const Tensor& quats,
                               const Tensor& colors, const Tensor& opacities, const Tensor& K, const Tensor& T_cw,
                               int64_t width, int64_t height, const RenderOptions& options, const RenderMaps& maps) {
    const CameraParams cam = camera_params(K, T_cw, width, height);
    const ProjectSettings ps{options.near, options.dilation, options.antialiased};
    const Projection proj = project_fwd(means, scales, quats, colors, opacities, cam, ps);
    static const char* names[5] = {"means", "scales", "quats", "colors", "opacities"};
    for (int k = 0; k < 5; ++k) check_no_nonfinite(proj.nonfinite[k], names[k]);  // counted by the projection pass
    const TileBins bins = bin_tiles(proj, cam);
    const bool plane = options.depth == "plane";
    // Group hits only where a backward may follow (the inputs that take gradients are means to opacities).
    const bool backward = means.requires_grad() || scales.requires_grad() || quats.requires_grad() ||
                          colors.requires_grad() || opacities.requires_grad();
    RasterOutput out = rasterize_fwd(proj.packed, bins, cam, options.background.data(),
                                     {maps.normals, plane, backward, maps.depth_map});
    // Outputs no loss reads get undefined gradients, so a colour-only loss runs the backward's colour-only loops.
    ctx->set_materialize_grads(false);
    ctx->save_for_backward({means, scales, quats, opacities, K, T_cw, proj.packed, bins.tile_offsets, bins.isect_ids,
                            out.final_T, out.n_contrib, out.group_hits});
    ctx->saved_data["width"] = width;
    ctx->saved_data["height"] = height;
    ctx->saved_data["near"] = options.near;
    ctx->saved_data["dilation"] = options.dilation;
    ctx->saved_data["antialiased"] = options.antialiased;
    ctx->saved_data["background"] = options.background;
    ctx->saved_data["plane_depth"] = plane;
    const Tensor median =
        maps.median_depth ? rasterize_median_depth(proj.packed, bins, cam, plane) : torch::empty({0}, means.options());
    if (plane || out.depth.numel() == 0)
      ctx->mark_non_differentiable({out.normal, out.depth, median});
    else
      ctx->mark_non_differentiable({out.normal, median});
    return {out.rgb, out.alpha, out.depth, out.normal, median};
  }

  static variable_list backward(AutogradContext* ctx, variable_list grads) {
    const auto saved = ctx->get_saved_variables();
    const Tensor &means = saved[0], &scales = saved[1], &quats = saved[2], &opacities = saved[3];
    const CameraParams cam =
        camera_params(saved[4], saved[5], ctx->saved_data["width"].toInt(), ctx->saved_data["height"].toInt());
    const Settings s = settings_from(ctx);
    const TileBins bins{saved[7], saved[8]};
    const Tensor grad_depth = ctx->saved_data["plane_depth"].toBool() ? Tensor() : grads[2];  // plane depth: none
    const Tensor grad2d = rasterize_bwd(saved[6], bins, cam, s.background, saved[9], saved[10], grads[0], grads[1],
                                        grad_depth, saved[11]);
    variable_list out(11);  // one per forward input: 7 tensors, width, height, options, maps
    if (ctx->needs_input_grad(3)) out[3] = grad2d.narrow(1, 6, 3).contiguous();  // colours: columns r, g, b
    if (ctx->needs_input_grad(0) || ctx->needs_input_grad(1) || ctx->needs_input_grad(2) || ctx->needs_input_grad(4)) {
      ProjectGrads g = project_bwd(means, scales, quats, opacities, cam, s.project, grad2d);
      out[0] = g.means, out[1] = g.scales, out[2] = g.quats, out[4] = g.opacities;
    }
    return out;
  }
};

Tensor checked(const Tensor& t, const char* name, int64_t n, int64_t cols, torch::Dtype dtype) {
  ISPLAT_CHECK(t.defined(), "render: ", name, " is undefined");
  ISPLAT_CHECK(t.device().is_cpu(), "render: ", name, " must be on the CPU, got ", t.device());
  ISPLAT_CHECK(t.scalar_type() == dtype, "render: ", name, " has dtype ", t.scalar_type(), ", expected ", dtype,
               " like means");
  const bool ok = cols == 0 ? (t.dim() == 1 && t.size(0) == n) || (t.dim() == 2 && t.size(0) == n && t.size(1) == 1)
                            : t.dim() == 2 && t.size(0) == n && t.size(1) == cols;
  ISPLAT_CHECK(ok, "render: ", name, " must be [", n, cols == 0 ? "" : cat(", ", cols), "], got ", t.sizes());
  return (cols == 0 ? t.reshape({n}) : t).contiguous();
}

RenderOutput render_one(const Gaussians& g, const Camera& cam, const RenderOptions& options, const RenderMaps& maps) {
  ISPLAT_CHECK(g.means.defined() && g.means.dim() == 2 && g.means.size(1) == 3, "render: means must be [N, 3], got ",
               g.means.defined() ? g.means.sizes() : c10::IntArrayRef{});
  const auto dtype = g.means.scalar_type();
  ISPLAT_CHECK(dtype == torch::kFloat32 || dtype == torch::kFloat64,
               "render: Gaussians must be float32 or float64, got ", dtype);
  const int64_t n = g.means.size(0);
  ISPLAT_CHECK(n < (int64_t(1) << 31), "render: too many Gaussians (", n, ")");
  const Tensor means = checked(g.means, "means", n, 3, dtype), scales = checked(g.scales, "scales", n, 3, dtype);
  const Tensor quats = checked(g.quats, "quats", n, 4, dtype), colors = checked(g.colors, "colors", n, 3, dtype);
  const Tensor opacities = checked(g.opacities, "opacities", n, 0, dtype);
  ISPLAT_CHECK(cam.K.defined() && cam.K.dim() == 2 && cam.K.size(0) == 3 && cam.K.size(1) == 3,
               "render: camera K must be [3, 3]");
  ISPLAT_CHECK(cam.T_cw.defined() && cam.T_cw.dim() == 2 && cam.T_cw.size(0) == 4 && cam.T_cw.size(1) == 4,
               "render: camera T_cw must be [4, 4]");
  camera_params(cam.K, cam.T_cw, cam.width, cam.height, /*validate=*/true);
  const auto outs = SplatFunction::apply(means, scales, quats, colors, opacities, cam.K, cam.T_cw, cam.width,
                                         cam.height, options, maps);
  return {outs[0], outs[1], outs[2], outs[3], maps.median_depth ? outs[4] : Tensor()};
}

}  // namespace
}  // namespace splat

RenderOutput render(const Gaussians& gaussians, const Camera& camera, const RenderOptions& options,
                    const RenderMaps& maps) {
  ISPLAT_CHECK(options.background.size() == 3, "render: background must have 3 values, got ",
               options.background.size());
  for (double b : options.background) ISPLAT_CHECK(std::isfinite(b), "render: background is not finite");
  ISPLAT_CHECK(options.near > 0 && std::isfinite(options.near), "render: near must be > 0, got ", options.near);
  ISPLAT_CHECK(options.dilation >= 0 && std::isfinite(options.dilation), "render: dilation must be >= 0, got ",
               options.dilation);
  ISPLAT_CHECK(options.depth == "center" || options.depth == "plane", "render: depth must be center or plane, got '",
               options.depth, "'");
  ISPLAT_CHECK(camera.width > 0 && camera.height > 0, "render: image size must be positive, got ", camera.width, "x",
               camera.height);
  ISPLAT_CHECK(gaussians.means.defined(), "render: means is undefined");
  const bool set_batched = gaussians.batched();
  const int64_t cam_batch = camera.batch();
  if (!set_batched && cam_batch == 0) return splat::render_one(gaussians, camera, options, maps);
  ISPLAT_CHECK(!set_batched || cam_batch == 0 || gaussians.batch() == cam_batch, "render: ", gaussians.batch(),
               " Gaussian sets but ", cam_batch, " cameras");
  ISPLAT_CHECK(camera.K.dim() == camera.T_cw.dim(), "render: camera K and T_cw must both be batched or both not");
  const int64_t B = set_batched ? gaussians.batch() : cam_batch;
  std::vector<torch::Tensor> rgb, alpha, depth, normal, median;
  for (int64_t b = 0; b < B; ++b) {
    const RenderOutput o = splat::render_one(set_batched ? gaussians.select(b) : gaussians,
                                             cam_batch > 0 ? camera.select(b) : camera, options, maps);
    rgb.push_back(o.rgb), alpha.push_back(o.alpha), depth.push_back(o.depth), normal.push_back(o.normal);
    if (maps.median_depth) median.push_back(o.median_depth);
  }
  return {torch::stack(rgb), torch::stack(alpha), torch::stack(depth), torch::stack(normal),
          maps.median_depth ? torch::stack(median) : torch::Tensor()};
}

}  // namespace isplat
