// The renderer for Python: render() on tensors straight from Python, and the SIMD level and thread count it uses.
#include <ATen/Parallel.h>

#include <string>
#include <vector>

#include "bindings.h"
#include "core/error.h"
#include "core/runtime.h"
#include "render/kernels.h"
#include "render/render.h"

namespace isplat::python {
namespace py = pybind11;
namespace {

// The outputs carry the C++ renderer's autograd node (render/splat_function.cpp), so backward() from Python runs
// its analytic backward pass; the GIL is released while it renders.
py::tuple render_tensors(const torch::Tensor& means, const torch::Tensor& quats, const torch::Tensor& scales,
                         const torch::Tensor& opacities, const torch::Tensor& colors, const torch::Tensor& K,
                         const torch::Tensor& T_cw, int64_t width, int64_t height,
                         const std::vector<double>& background, double near_plane, double eps2d, bool antialiased,
                         const std::string& depth_mode, bool with_depth, bool with_normal) {
  RenderOptions options;
  options.background = background;
  options.near = near_plane;
  options.dilation = eps2d;
  options.antialiased = antialiased;
  options.depth = depth_mode;
  RenderMaps maps;
  maps.normals = with_normal;
  maps.depth_map = with_depth;
  RenderOutput out;
  {
    py::gil_scoped_release no_gil;
    out = render(Gaussians{means, scales, quats, colors, opacities}, Camera{K, T_cw, width, height}, options, maps);
  }
  return py::make_tuple(out.rgb, out.alpha, with_depth ? out.depth : torch::Tensor(),
                        with_normal ? out.normal : torch::Tensor());
}

splat::Simd simd_from_name(const std::string& name) {
  for (auto level : {splat::Simd::portable, splat::Simd::avx2, splat::Simd::avx512})
    if (name == splat::simd_name(level)) return level;
  fail("set_simd_level: level '", name, "' is not portable, avx2 or avx512");
}

}  // namespace

void bind_render(py::module_& m) {
  m.def("render", &render_tensors, py::arg("means"), py::arg("quats"), py::arg("scales"), py::arg("opacities"),
        py::arg("colors"), py::arg("K"), py::arg("T_cw"), py::arg("width"), py::arg("height"), py::arg("background"),
        py::arg("near_plane"), py::arg("eps2d"), py::arg("antialiased"), py::arg("depth_mode"), py::arg("with_depth"),
        py::arg("with_normal"));
  m.def("simd_level", [] { return std::string(splat::simd_name(splat::simd_level())); });
  m.def("simd_supported", [] { return std::string(splat::simd_name(splat::simd_supported())); });
  m.def("set_simd_level", [](const std::string& name) {
    return std::string(splat::simd_name(splat::set_simd_level(simd_from_name(name))));
  });
  m.def("num_threads", [] { return at::get_num_threads(); });
  m.def("set_num_threads", [](int64_t n) {
    ISPLAT_CHECK(n >= 0 && n <= kMaxThreads, "set_num_threads: n = ", n, " is outside [0, ", kMaxThreads, "]");
    return configure_threads(n);
  });
}

}  // namespace isplat::python
