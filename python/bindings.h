// The extension module's parts (infinisplat._C), each filling the module in its own file.
#pragma once
#include <torch/extension.h>

namespace isplat::python {

void bind_render(pybind11::module_& m);   // bindings_render.cpp: render, SIMD level, threads
void bind_predict(pybind11::module_& m);  // bindings_predict.cpp: Predictor, PLY, image and depth readers

}  // namespace isplat::python
