// The predictor for Python (one photo -> Gaussians, as `infinisplat predict` makes them) and the PLY, image and
// depth readers and writer it needs.
#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "bindings.h"
#include "core/config.h"
#include "core/error.h"
#include "core/runtime.h"
#include "geometry/camera_torch.h"
#include "geometry/image_ops.h"
#include "io/atomic_file.h"
#include "io/checkpoint.h"
#include "io/depth_io.h"
#include "io/exif.h"
#include "io/image_io.h"
#include "io/ply.h"
#include "io/tensor_image.h"
#include "model/model_io.h"
#include "render/prune.h"

namespace isplat::python {
namespace py = pybind11;
namespace {

// The same defaults and rules as cli/cmd_predict.cpp's for one photo: the working size is the training
// resolution's area at the photo's aspect in multiples of 16, unless width and height are given.
std::pair<int, int> working_size(const Checkpoint& ck, int width, int height, int64_t override_w, int64_t override_h) {
  if (override_w > 0 && override_h > 0) return {static_cast<int>(override_w), static_cast<int>(override_h)};
  int64_t tw = 256, th = 192;
  try {
    const auto cfg = parse_json(ck.config_json(), "stored config");
    tw = cfg.at("data").at("tuples").at("width").get<int64_t>();
    th = cfg.at("data").at("tuples").at("height").get<int64_t>();
  } catch (const std::exception&) {  // no training size stored (a converted checkpoint): the CLI's default
  }
  if (tw < 16 || th < 16 || tw > max_image_pixels() / th) tw = 256, th = 192;
  auto r16 = [](double x) { return std::max(16, static_cast<int>(std::lround(x / 16.0)) * 16); };
  const double area = static_cast<double>(tw) * th, aspect = static_cast<double>(width) / height;
  return {r16(std::sqrt(area * aspect)), r16(std::sqrt(area / aspect))};
}

// An sRGB image as float [3, H, W] on the CPU (values are clamped to [0, 1] where they are written).
torch::Tensor checked_image(const torch::Tensor& image) {
  ISPLAT_CHECK(image.defined() && image.device().is_cpu(), "image must be a CPU tensor");
  ISPLAT_CHECK(image.dim() == 3 && image.size(0) == 3 && image.size(1) >= 1 && image.size(2) >= 1,
               "image must be [3, H, W], got ", image.sizes());
  ISPLAT_CHECK(image.is_floating_point(), "image must be float in [0, 1], got ", image.scalar_type());
  ISPLAT_CHECK(torch::isfinite(image).all().item<bool>(), "image has non-finite values");
  return image.detach().to(torch::kFloat32).contiguous();
}

class Predictor {
 public:
  Predictor(const std::string& checkpoint, const std::vector<std::string>& overrides) : path_(checkpoint) {
    ck_ = std::make_unique<Checkpoint>(load_checkpoint(checkpoint));
    pipeline_ = load_pipeline(*ck_, checkpoint, overrides);
    trained_floor_px_ = pipeline_->model()->options.composer.scale_floor_px;
  }

  bool linear_rgb() { return pipeline_->model()->options.composer.linear_rgb; }
  double hfov_deg() { return pipeline_->model()->options.prior.hfov_deg; }
  std::string prior_type() { return pipeline_->model()->options.prior.type; }

  // (means, quats, scales, opacities, colors, K [3,3] of the working size, width, height).
  py::tuple predict(const py::object& image_or_path, std::optional<double> fx, std::optional<double> fy,
                    std::optional<double> cx, std::optional<double> cy, std::optional<double> hfov,
                    std::optional<torch::Tensor> depth, int64_t width, int64_t height, int64_t seed, double view_floor,
                    double prune_opacity, double prune_contribution, int64_t prune_views, bool keep_outside) {
    cv::Mat photo;
    std::string exif_from;
    if (py::isinstance<py::str>(image_or_path)) {
      exif_from = image_or_path.cast<std::string>();
      photo = read_image(exif_from);
    } else {
      photo = tensor_to_image(checked_image(image_or_path.cast<torch::Tensor>()));
    }
    ISPLAT_CHECK((width > 0) == (height > 0), "predict: give width and height together (got ", width, "x", height, ")");
    ISPLAT_CHECK(width % 16 == 0 && height % 16 == 0 && width >= 0 && height >= 0, "predict: width ", width,
                 " and height ", height, " must be multiples of 16 (the encoder's patch)");
    ISPLAT_CHECK(fx || (!fy && !cx && !cy), "predict: fy, cx and cy refine fx; give fx too");
    ISPLAT_CHECK(!fx || (*fx > 0 && std::isfinite(*fx)), "predict: fx must be a positive focal length in pixels");
    ISPLAT_CHECK(!fy || (*fy > 0 && std::isfinite(*fy)), "predict: fy must be a positive focal length in pixels");
    ISPLAT_CHECK(!hfov || (*hfov >= 1 && *hfov <= 179), "predict: hfov must be in [1, 179] degrees");
    ISPLAT_CHECK(view_floor >= 0 && view_floor <= 4, "predict: view_floor must be in [0, 4] pixels");
    ISPLAT_CHECK(prune_opacity >= 0 && prune_opacity <= 1, "predict: prune_opacity must be in [0, 1]");
    ISPLAT_CHECK(prune_contribution >= 0 && prune_contribution <= 1, "predict: prune_contribution must be in [0, 1]");
    ISPLAT_CHECK(prune_views == 0 || prune_views == 2 || prune_views == 4 || prune_views == 6,
                 "predict: prune_views must be 0, 2, 4 or 6");
    const int W0 = photo.cols, H0 = photo.rows;
    ISPLAT_CHECK(!cx || (*cx >= 0 && *cx <= W0), "predict: cx must lie in the photo, [0, ", W0, "]");
    ISPLAT_CHECK(!cy || (*cy >= 0 && *cy <= H0), "predict: cy must lie in the photo, [0, ", H0, "]");

    Result r;
    {
      py::gil_scoped_release no_gil;
      r = run(photo, exif_from, fx, fy, cx, cy, hfov, depth, width, height, seed, view_floor, prune_opacity,
              prune_contribution, prune_views, keep_outside);
    }
    const Gaussians& g = r.g;
    return py::make_tuple(g.means, g.quats, g.scales, g.opacities, g.colors, r.K, r.width, r.height);
  }

 private:
  struct Result {
    Gaussians g;
    torch::Tensor K;
    int width = 0, height = 0;
  };

  // The prediction itself, without the GIL.
  Result run(const cv::Mat& photo, const std::string& exif_from, std::optional<double> fx, std::optional<double> fy,
             std::optional<double> cx, std::optional<double> cy, std::optional<double> hfov,
             const std::optional<torch::Tensor>& depth, int64_t width, int64_t height, int64_t seed, double view_floor,
             double prune_opacity, double prune_contribution, int64_t prune_views, bool keep_outside) {
    const int W0 = photo.cols, H0 = photo.rows;
    Intrinsics intr;
    const ExifFocal exif = exif_from.empty() || fx ? ExifFocal{} : read_exif_focal(read_file_bytes(exif_from));
    if (fx) {
      intr = {*fx, fy ? *fy : *fx, cx ? *cx : W0 / 2.0, cy ? *cy : H0 / 2.0, W0, H0};
    } else if (exif.focal_35mm) {
      const double f = fx_from_35mm(*exif.focal_35mm, W0, H0);
      intr = {f, f, W0 / 2.0, H0 / 2.0, W0, H0};
    } else {
      intr = Intrinsics::from_hfov((hfov ? *hfov : hfov_deg()) * M_PI / 180.0, W0, H0);
    }
    const auto [Wm, Hm] = working_size(*ck_, W0, H0, width, height);
    const View view{intr.resized(Wm, Hm), Pose::Identity()};
    PriorInput in;
    in.image = image_to_tensor(resize_image(photo, Wm, Hm));
    in.K = to_camera(view).K;
    in.seed = static_cast<uint64_t>(seed);
    if (depth) {  // metric planar depth in metres, the photo's own view at any size of its aspect
      const torch::Tensor d = *depth;
      ISPLAT_CHECK(d.device().is_cpu() && d.dim() == 2 && d.is_floating_point(),
                   "predict: depth must be a float CPU tensor [H, W], got ", d.sizes());
      const double ratio = (static_cast<double>(d.size(1)) / d.size(0)) / (static_cast<double>(W0) / H0);
      ISPLAT_CHECK(std::fabs(ratio - 1.0) <= 0.01, "predict: depth is ", d.size(1), "x", d.size(0),
                   ", not a resized copy of the photo's view (", W0, "x", H0, "): the aspects differ");
      in.depth = map_to_tensor(resize_depth(tensor_to_map(d.detach().to(torch::kFloat32).contiguous()), Wm, Hm));
      in.valid = (in.depth > 0).to(torch::kFloat32);
    }
    double& floor_px = pipeline_->model()->options.composer.scale_floor_px;
    floor_px = std::max(trained_floor_px_, view_floor);
    const Prediction pred = pipeline_->run(in, torch::eye(4), false);
    Gaussians g = pred.gaussians;
    if (!keep_outside) {  // centres that leave the source view go, as the CLI drops them
      auto uv = project_points(g.means, in.K);
      auto keep = (g.means.select(1, 2) > 0) & (uv.select(1, 0) >= 0) & (uv.select(1, 0) < Wm) &
                  (uv.select(1, 1) >= 0) & (uv.select(1, 1) < Hm);
      g = g.index(keep);
    }
    PruneOptions po;
    po.enabled = true;
    po.min_opacity = prune_opacity;
    po.min_contribution = prune_contribution;
    po.views = prune_views;
    g = prune_gaussians(g, to_camera(view), po).kept;
    return {g, in.K, Wm, Hm};
  }

  std::string path_;
  std::unique_ptr<Checkpoint> ck_;
  std::unique_ptr<Pipeline> pipeline_;
  double trained_floor_px_ = 0;
};

}  // namespace

void bind_predict(py::module_& m) {
  py::class_<Predictor>(m, "Predictor")
      .def(py::init<const std::string&, const std::vector<std::string>&>(), py::arg("checkpoint"), py::arg("overrides"))
      .def_property_readonly("linear_rgb", &Predictor::linear_rgb)
      .def_property_readonly("hfov_deg", &Predictor::hfov_deg)
      .def_property_readonly("prior_type", &Predictor::prior_type)
      .def("predict", &Predictor::predict, py::arg("image"), py::arg("fx"), py::arg("fy"), py::arg("cx"), py::arg("cy"),
           py::arg("hfov"), py::arg("depth"), py::arg("width"), py::arg("height"), py::arg("seed"),
           py::arg("view_floor"), py::arg("prune_opacity"), py::arg("prune_contribution"), py::arg("prune_views"),
           py::arg("keep_outside"));
  m.def(
      "write_ply",
      [](const std::string& path, const torch::Tensor& means, const torch::Tensor& quats, const torch::Tensor& scales,
         const torch::Tensor& opacities, const torch::Tensor& colors, bool colors_linear, int sh_degree) {
        PlyOptions options;
        options.sh_degree = sh_degree;
        write_ply(path, Gaussians{means, scales, quats, colors, opacities}.detach(), colors_linear, options);
      },
      py::arg("path"), py::arg("means"), py::arg("quats"), py::arg("scales"), py::arg("opacities"), py::arg("colors"),
      py::arg("colors_linear"), py::arg("sh_degree"));
  m.def(
      "read_ply",
      [](const std::string& path, bool want_linear) {
        const Gaussians g = read_ply(path, want_linear);
        return py::make_tuple(g.means, g.quats, g.scales, g.opacities, g.colors);
      },
      py::arg("path"), py::arg("want_linear"));
  m.def(
      "read_image", [](const std::string& path) { return image_to_tensor(read_image(path)); }, py::arg("path"));
  m.def(
      "write_image",
      [](const std::string& path, const torch::Tensor& image) {
        write_image(path, tensor_to_image(checked_image(image)));
      },
      py::arg("path"), py::arg("image"));
  m.def(
      "read_depth", [](const std::string& path) { return map_to_tensor(read_depth_exr(path).depth); }, py::arg("path"));
}

}  // namespace isplat::python
