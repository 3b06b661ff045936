// Central finite differences against autograd, element by element.
#include "support/finite_diff.h"

#include <torch/torch.h>

#include <algorithm>
#include <sstream>

namespace isplat::test {

GradCheck check_gradients(const std::function<torch::Tensor(const std::vector<torch::Tensor>&)>& f,
                          const std::vector<torch::Tensor>& inputs, const std::vector<std::string>& names, double eps,
                          double atol, double rtol) {
  std::vector<torch::Tensor> x;
  for (const auto& t : inputs) x.push_back(t.detach().to(torch::kFloat64).clone().requires_grad_(true));
  const torch::Tensor out = f(x);
  const int64_t K = out.numel();
  std::vector<std::vector<torch::Tensor>> analytic;  // [K][inputs]
  for (int64_t k = 0; k < K; ++k) {
    auto g = torch::autograd::grad({out[k]}, x, {}, /*retain_graph=*/true, /*create_graph=*/false,
                                   /*allow_unused=*/true);
    for (size_t i = 0; i < g.size(); ++i)
      if (!g[i].defined()) g[i] = torch::zeros_like(x[i]);
    analytic.push_back(g);
  }
  GradCheck result;
  struct Miss {
    double err;
    std::string text;
  };
  std::vector<Miss> misses;
  torch::NoGradGuard no_grad;
  std::vector<torch::Tensor> probe;
  for (const auto& t : x) probe.push_back(t.detach().clone());
  for (size_t i = 0; i < probe.size(); ++i) {
    auto flat = probe[i].view({-1});
    for (int64_t j = 0; j < flat.numel(); ++j) {
      const double x0 = flat[j].item<double>();
      flat[j] = x0 + eps;
      const torch::Tensor plus = f(probe).detach().clone();
      flat[j] = x0 - eps;
      const torch::Tensor minus = f(probe).detach().clone();
      flat[j] = x0;
      const torch::Tensor numeric = (plus - minus) / (2 * eps);
      for (int64_t k = 0; k < K; ++k) {
        const double num = numeric[k].item<double>();
        const double ana = analytic[k][i].reshape({-1})[j].item<double>();
        const double err = std::abs(ana - num);
        ++result.checked;
        result.max_abs_error = std::max(result.max_abs_error, err);
        if (err > atol + rtol * std::abs(num)) {
          result.ok = false;
          std::ostringstream os;
          os << names[i] << "[" << j << "] output " << k << ": analytic " << ana << " numeric " << num;
          misses.push_back({err, os.str()});
        }
      }
    }
  }
  std::sort(misses.begin(), misses.end(), [](const Miss& a, const Miss& b) { return a.err > b.err; });
  for (size_t m = 0; m < std::min<size_t>(misses.size(), 10); ++m) result.report += misses[m].text + "\n";
  return result;
}

}  // namespace isplat::test
