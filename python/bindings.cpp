// infinisplat._C: the project's C++ library as a PyTorch extension; isplat::Error becomes infinisplat.Error.
#include "bindings.h"

#include "core/error.h"

PYBIND11_MODULE(TORCH_EXTENSION_NAME, m) {
  m.doc() = "InfiniSplat-C++ as a PyTorch extension (the Python API is in infinisplat/__init__.py)";
  m.attr("__version__") = ISPLAT_VERSION;
  // A RuntimeError subclass carrying the C++ message, which names the argument, file or key at fault.
  pybind11::register_exception<isplat::Error>(m, "Error", PyExc_RuntimeError);
  isplat::python::bind_render(m);
  isplat::python::bind_predict(m);
}
