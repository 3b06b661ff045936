// The predictor for Python (one photo -> Gaussians through src/predict/, as `infinisplat predict` makes them) and
// the PLY, image and depth readers and writer it needs.
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "bindings.h"
#include "core/error.h"
#include "io/depth_io.h"
#include "io/image_io.h"
#include "io/ply.h"
#include "io/tensor_image.h"
#include "predict/photo.h"

namespace isplat::python {
namespace py = pybind11;
namespace {

// An sRGB image as float [3, H, W] on the CPU (values are clamped to [0, 1] where they are written).
torch::Tensor checked_image(const torch::Tensor& image) {
  ISPLAT_CHECK(image.defined() && image.device().is_cpu(), "image must be a CPU tensor");
  ISPLAT_CHECK(image.dim() == 3 && image.size(0) == 3 && image.size(1) >= 1 && image.size(2) >= 1,
               "image must be [3, H, W], got ", image.sizes());
  ISPLAT_CHECK(image.is_floating_point(), "image must be float in [0, 1], got ", image.scalar_type());
  ISPLAT_CHECK(torch::isfinite(image).all().item<bool>(), "image has non-finite values");
  return image.detach().to(torch::kFloat32).contiguous();
}

// A checkpoint loaded once; predict() makes `infinisplat predict`'s Gaussians (src/predict/photo.h, which both call).
class Predictor {
 public:
  Predictor(const std::string& checkpoint, const std::vector<std::string>& overrides)
      : predictor_(std::make_unique<PhotoPredictor>(checkpoint, overrides)) {}

  bool linear_rgb() { return model().options.composer.linear_rgb; }
  double hfov_deg() { return model().options.prior.hfov_deg; }
  std::string prior_type() { return model().options.prior.type; }

  // (means, quats, scales, opacities, colors, K [3,3] of the working size, width, height).
  py::tuple predict(const py::object& image_or_path, std::optional<double> fx, std::optional<double> fy,
                    std::optional<double> cx, std::optional<double> cy, std::optional<double> hfov,
                    std::optional<torch::Tensor> depth, int64_t width, int64_t height, int64_t seed,
                    std::optional<double> view_floor, std::optional<double> prune_opacity,
                    std::optional<double> prune_contribution, std::optional<int64_t> prune_views, bool keep_outside) {
    PhotoInput input;
    if (py::isinstance<py::str>(image_or_path)) {
      input.exif_from = input.label = image_or_path.cast<std::string>();
      input.photo = read_image(input.label);
    } else {
      input.photo = tensor_to_image(checked_image(image_or_path.cast<torch::Tensor>()));
      input.label = "tensor";
    }
    if (depth) {  // metric planar depth in metres, the photo's own view at any size of its aspect
      const torch::Tensor& d = *depth;
      ISPLAT_CHECK(d.device().is_cpu() && d.dim() == 2 && d.numel() > 0 && d.is_floating_point(),
                   "predict: depth must be a float CPU tensor [H, W], got ", d.sizes());
      input.depth = tensor_to_map(d.detach().to(torch::kFloat32).contiguous());
    }
    PhotoPredictOptions options;
    options.names = OptionNames::Keywords;
    options.intrinsics = {fx, fy, cx, cy, hfov};
    options.width = width, options.height = height, options.seed = static_cast<uint64_t>(seed);
    // Not given: PhotoPredictOptions' defaults, which are the CLI's (one place holds them).
    if (view_floor) options.view_floor = *view_floor;
    if (prune_opacity) options.prune_opacity = *prune_opacity;
    if (prune_contribution) options.prune_contribution = *prune_contribution;
    if (prune_views) options.prune_views = *prune_views;
    options.keep_outside = keep_outside;
    PhotoPrediction r;
    {
      py::gil_scoped_release no_gil;
      r = predictor_->predict(input, options);
    }
    const Gaussians& g = r.gaussians;
    return py::make_tuple(g.means, g.quats, g.scales, g.opacities, g.colors, r.frame.input.K, r.frame.width,
                          r.frame.height);
  }

 private:
  InfiniSplatImpl& model() { return *predictor_->pipeline().model(); }

  std::unique_ptr<PhotoPredictor> predictor_;
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
