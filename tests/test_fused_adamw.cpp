// The one-pass AdamW: the same updates as LibTorch's AdamW (to float rounding), on its state and archives.
#include <catch2/catch.hpp>

#include <torch/torch.h>

#include <sstream>

#include "train/fused_adamw.h"

namespace isplat::fused_adamw_test {

// Parameters of a few shapes (one large enough to split across threads, sizes that are no multiple of a vector) and
// fixed gradients per step.
std::vector<torch::Tensor> parameters() {
  torch::manual_seed(7);
  return {torch::randn({70001}), torch::randn({13, 7}), torch::randn({3})};
}
void set_gradients(std::vector<torch::Tensor>& params, int step) {
  for (size_t k = 0; k < params.size(); ++k) {
    torch::manual_seed(100 * step + int64_t(k));
    params[k].mutable_grad() = torch::randn_like(params[k]) * (k == 2 ? 1e-6 : 1.0);  // a near-zero one too
  }
}
std::vector<torch::Tensor> leaves(const std::vector<torch::Tensor>& values) {
  std::vector<torch::Tensor> out;
  for (const auto& v : values) out.push_back(v.detach().clone().set_requires_grad(true));
  return out;
}
torch::optim::AdamWOptions options() {
  return torch::optim::AdamWOptions(3e-3).betas({0.9, 0.99}).weight_decay(0.05).eps(1e-8);
}
// The largest difference, relative to the largest value: a few float roundings of values near 1 stay far below 1e-6.
double max_relative(const torch::Tensor& a, const torch::Tensor& b) {
  return ((a - b).abs().max() / b.abs().max()).item<double>();
}

TEST_CASE("fused AdamW: twenty steps match LibTorch's AdamW to float rounding, per group options included",
          "[train][optim]") {
  const auto start = parameters();
  auto ours = leaves(start), theirs = leaves(start);
  auto groups = [&](std::vector<torch::Tensor>& p) {
    std::vector<torch::optim::OptimizerParamGroup> g;
    g.emplace_back(std::vector<torch::Tensor>{p[0], p[1]}, std::make_unique<torch::optim::AdamWOptions>(options()));
    g.emplace_back(std::vector<torch::Tensor>{p[2]},
                   std::make_unique<torch::optim::AdamWOptions>(options().lr(1e-2).weight_decay(0)));
    return g;
  };
  FusedAdamW fused(groups(ours), options());
  torch::optim::AdamW reference(groups(theirs), options());
  for (int step = 0; step < 20; ++step) {
    set_gradients(ours, step);
    set_gradients(theirs, step);
    fused.step();
    reference.step();
    CHECK(fused.fused_in_last_step() == 3);  // every parameter took the one-pass loop
  }
  for (size_t k = 0; k < ours.size(); ++k) {
    INFO("parameter " << k);
    CHECK(max_relative(ours[k], theirs[k]) < 1e-6);
    CHECK_FALSE(torch::equal(ours[k], start[k]));  // they moved
  }
}

// Three steps with `first`, its archive loaded into `second`, then three more steps each: returns both parameter sets.
template <class First, class Second>
std::pair<std::vector<torch::Tensor>, std::vector<torch::Tensor>> continued_after_loading() {
  auto before = leaves(parameters());
  First first(before, options());
  for (int step = 0; step < 3; ++step) {
    set_gradients(before, step);
    first.step();
  }
  std::stringstream saved;
  torch::serialize::OutputArchive out;
  first.save(out);
  out.save_to(saved);
  auto after = leaves(before);
  Second second(after, options());
  torch::serialize::InputArchive in;
  in.load_from(saved);
  second.load(in);
  for (int step = 3; step < 6; ++step) {
    set_gradients(before, step);
    set_gradients(after, step);
    first.step();
    second.step();
  }
  return {before, after};
}

TEST_CASE("fused AdamW: archives load in both directions between it and LibTorch's AdamW, and training continues",
          "[train][optim]") {
  const auto [ours, ours_resumed] = continued_after_loading<FusedAdamW, FusedAdamW>();
  const auto [ours_then, theirs_resumed] = continued_after_loading<FusedAdamW, torch::optim::AdamW>();
  const auto [theirs_then, ours_after_theirs] = continued_after_loading<torch::optim::AdamW, FusedAdamW>();
  for (size_t k = 0; k < ours.size(); ++k) {
    INFO("parameter " << k);
    CHECK(torch::equal(ours_resumed[k], ours[k]));  // resuming our own archive is exact
    CHECK(max_relative(theirs_resumed[k], ours_then[k]) < 1e-6);
    CHECK(max_relative(ours_after_theirs[k], theirs_then[k]) < 1e-6);
  }
}

// Five steps of both optimizers on one parameter made by `make`, its gradients made by `grad_of`; returns how many
// parameters our last step fused.
template <class Make, class Grad>
int64_t compare_on(Make make, Grad grad_of, const torch::optim::AdamWOptions& opts) {
  std::vector<torch::Tensor> ours{make()}, theirs{make()};
  FusedAdamW fused(ours, opts);
  torch::optim::AdamW reference(theirs, opts);
  for (int step = 0; step < 5; ++step) {
    torch::manual_seed(step);
    ours[0].mutable_grad() = grad_of(ours[0]);
    torch::manual_seed(step);
    theirs[0].mutable_grad() = grad_of(theirs[0]);
    fused.step();
    reference.step();
  }
  CHECK(max_relative(ours[0], theirs[0]) < 1e-6);
  CHECK_FALSE(torch::equal(ours[0], make()));
  return fused.fused_in_last_step();
}

TEST_CASE("fused AdamW: amsgrad, a non-contiguous parameter or gradient take LibTorch's operations, with its result",
          "[train][optim]") {
  torch::manual_seed(3);
  const torch::Tensor base = torch::randn({8, 6});
  auto contiguous = [&] { return base.clone().set_requires_grad(true); };
  auto transposed = [&] { return base.t().clone().set_requires_grad(true); };  // clone keeps the transposed strides
  REQUIRE_FALSE(transposed().is_contiguous());
  auto like = [](const torch::Tensor& p) { return torch::randn_like(p); };
  auto transposed_grad = [](const torch::Tensor& p) { return torch::randn({p.size(1), p.size(0)}).t(); };
  CHECK(compare_on(contiguous, like, options()) == 1);  // the one-pass loop
  CHECK(compare_on(contiguous, like, options().amsgrad(true)) == 0);
  CHECK(compare_on(transposed, like, options()) == 0);
  CHECK(compare_on(contiguous, transposed_grad, options()) == 0);
}

TEST_CASE("fused AdamW: a parameter without a gradient is left alone and gets no state, and fused writes bump versions",
          "[train][optim]") {
  auto p = leaves(parameters());
  FusedAdamW fused(p, options());
  const torch::Tensor before = p[1].detach().clone();
  p[0].mutable_grad() = torch::ones_like(p[0]);
  p[2].mutable_grad() = torch::ones_like(p[2]);
  const auto version = p[0]._version();
  fused.step();
  CHECK(fused.fused_in_last_step() == 2);
  CHECK(torch::equal(p[1], before));
  CHECK(fused.state().size() == 2);
  CHECK(p[0]._version() > version);  // autograd sees the in-place change
}

}  // namespace isplat::fused_adamw_test
