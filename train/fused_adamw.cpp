// One pass per parameter for AdamW: decay, both moments and the update in a single loop over memory.
#include "train/fused_adamw.h"

#include <ATen/Parallel.h>
#include <c10/util/string_utils.h>

#include <cmath>

namespace isplat {
namespace {

struct StepScalars {
  float decay, beta1, one_minus_beta1, beta2, one_minus_beta2, bias2_sqrt, eps, neg_step_size;
};

// LibTorch's AdamW step for elements [begin, end) of one contiguous float tensor, rounded as its vectorized kernels
// round (x86 with FMA): p·decay; fma(g, 1 − β1, m·β1); fma((1 − β2)·g, g, v·β2); p + (−step)·m / (√v / √bc2 + ε).
// One clone per instruction set: only with FMA in the target is std::fma an instruction the loop can vectorize (else
// a call to libm). The file is built with -ffp-contract=off (no other product is fused) and -fno-math-errno (the
// square root vectorizes too: v is never negative).
#if defined(__x86_64__)
#define ISPLAT_OPTIMIZER_CLONES __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define ISPLAT_OPTIMIZER_CLONES
#endif
ISPLAT_OPTIMIZER_CLONES void update_range(float* __restrict p, const float* __restrict g, float* __restrict m,
                                          float* __restrict v, int64_t begin, int64_t end, const StepScalars& s,
                                          bool decay) {
  for (int64_t i = begin; i < end; ++i) {
    float pi = p[i];
    if (decay) pi = pi * s.decay;
    const float gi = g[i];
    const float mi = std::fma(gi, s.one_minus_beta1, m[i] * s.beta1);       // as LibTorch's vectorized add_
    const float vi = std::fma(s.one_minus_beta2 * gi, gi, v[i] * s.beta2);  // as its addcmul_
    const float denom = std::sqrt(vi) / s.bias2_sqrt + s.eps;
    p[i] = pi + s.neg_step_size * mi / denom;
    m[i] = mi, v[i] = vi;
  }
}

void fused_update(float* p, const float* g, float* m, float* v, int64_t n, const StepScalars& s, bool decay) {
  at::parallel_for(0, n, 1 << 15, [&](int64_t begin, int64_t end) { update_range(p, g, m, v, begin, end, s, decay); });
}

}  // namespace

torch::Tensor FusedAdamW::step(LossClosure closure) {
  torch::NoGradGuard no_grad;
  torch::Tensor loss;
  if (closure) {
    at::AutoGradMode enable_grad(true);
    loss = closure();
  }
  fused_in_last_step_ = 0;
  for (auto& group : param_groups_) {
    const auto& o = static_cast<const torch::optim::AdamWOptions&>(group.options());
    const double lr = o.lr(), beta1 = std::get<0>(o.betas()), beta2 = std::get<1>(o.betas());
    for (auto& p : group.params()) {
      if (!p.grad().defined()) continue;
      const torch::Tensor& grad = p.grad();
      TORCH_CHECK(!grad.is_sparse(), "FusedAdamW does not support sparse gradients");
      const std::string key = c10::guts::to_string(p.unsafeGetTensorImpl());  // the key LibTorch's AdamW uses
      auto found = state_.find(key);
      if (found == state_.end()) {
        auto fresh = std::make_unique<torch::optim::AdamWParamState>();
        fresh->step(0);
        fresh->exp_avg(torch::zeros_like(p, torch::MemoryFormat::Preserve));
        fresh->exp_avg_sq(torch::zeros_like(p, torch::MemoryFormat::Preserve));
        if (o.amsgrad()) fresh->max_exp_avg_sq(torch::zeros_like(p, torch::MemoryFormat::Preserve));
        found = state_.emplace(key, std::move(fresh)).first;
      }
      auto& state = static_cast<torch::optim::AdamWParamState&>(*found->second);
      state.step(state.step() + 1);
      const double bias1 = 1 - std::pow(beta1, double(state.step()));
      const double bias2 = 1 - std::pow(beta2, double(state.step()));
      const double step_size = lr / bias1, decay = 1 - lr * o.weight_decay();
      torch::Tensor& m = state.exp_avg();
      torch::Tensor& v = state.exp_avg_sq();
      // One flat loop needs four contiguous float tensors of one shape (a loaded state of another shape, say, takes
      // LibTorch's operations, which refuse it).
      auto flat_float = [&](const torch::Tensor& t) {
        return t.scalar_type() == torch::kFloat32 && t.is_contiguous() && t.device().is_cpu() && t.sizes() == p.sizes();
      };
      const bool fused = !o.amsgrad() && flat_float(p) && flat_float(grad) && flat_float(m) && flat_float(v);
      if (fused) {
        const StepScalars s{float(decay),   float(beta1),     float(1 - beta1),
                            float(beta2),   float(1 - beta2), float(std::sqrt(bias2)),
                            float(o.eps()), float(-step_size)};
        fused_update(p.data_ptr<float>(), grad.data_ptr<float>(), m.data_ptr<float>(), v.data_ptr<float>(), p.numel(),
                     s, o.weight_decay() != 0);
        // Written through raw pointers: bump the version counters as in-place operations do, so autograd still
        // notices a saved tensor that changed.
        for (const torch::Tensor* t : {&p, &m, &v}) t->unsafeGetTensorImpl()->bump_version();
        ++fused_in_last_step_;
        continue;
      }
      // LibTorch's AdamW::step, as tensor operations.
      if (o.weight_decay() != 0) p.mul_(decay);
      m.mul_(beta1).add_(grad, 1 - beta1);
      v.mul_(beta2).addcmul_(grad, grad, 1 - beta2);
      torch::Tensor denom;
      if (o.amsgrad()) {
        torch::Tensor& max_v = state.max_exp_avg_sq();
        torch::max_out(max_v, max_v, v);
        denom = (max_v.sqrt() / std::sqrt(bias2)).add_(o.eps());
      } else {
        denom = (v.sqrt() / std::sqrt(bias2)).add_(o.eps());
      }
      p.addcdiv_(m, denom, -step_size);
    }
  }
  return loss;
}

}  // namespace isplat
