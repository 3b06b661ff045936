// Generic gradient check: autograd gradients of any differentiable op against central finite differences.
#pragma once
#include <torch/types.h>

#include <functional>
#include <string>
#include <vector>

namespace isplat::test {

struct GradCheck {
  bool ok = true;
  double max_abs_error = 0;  // over all inputs, elements and outputs
  int64_t checked = 0;       // number of (element, output) pairs compared
  std::string report;        // the worst mismatches, one per line
};

// f maps the inputs (float64) to a 1-D tensor of K scalar outputs. Every element of every input is
// perturbed by ±eps; a pair passes when |analytic − numeric| ≤ atol + rtol·|numeric|.
GradCheck check_gradients(const std::function<torch::Tensor(const std::vector<torch::Tensor>&)>& f,
                          const std::vector<torch::Tensor>& inputs, const std::vector<std::string>& names,
                          double eps = 1e-6, double atol = 1e-7, double rtol = 1e-4);

}  // namespace isplat::test
