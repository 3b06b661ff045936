// The one-pass AdamW: the same updates as LibTorch's AdamW (to float rounding), on its state and archives.
#include <catch2/catch.hpp>

#include <torch/torch.h>

#include <sstream>

#include "train/fused_adamw.h"

namespace isplat::fused_adamw_test {

// Parameters of a few shapes (one large enough to split across threads, one not contiguous-friendly size) and
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
  }
  for (size_t k = 0; k < ours.size(); ++k) {
    INFO("parameter " << k);
    CHECK(max_relative(ours[k], theirs[k]) < 1e-6);
    CHECK_FALSE(torch::equal(ours[k], start[k]));  // they moved
  }
}

TEST_CASE("fused AdamW: its archive loads into LibTorch's AdamW and back, and training continues the same",
          "[train][optim]") {
  const auto start = parameters();
  auto ours = leaves(start);
  FusedAdamW fused(ours, options());
  for (int step = 0; step < 3; ++step) {
    set_gradients(ours, step);
    fused.step();
  }
  std::stringstream saved;
  {
    torch::serialize::OutputArchive archive;
    fused.save(archive);
    archive.save_to(saved);
  }
  // LibTorch's AdamW resumes from our archive, and ours from a copy of the same: the next steps agree.
  std::vector<torch::Tensor> theirs = leaves(ours), again = leaves(ours);
  torch::optim::AdamW reference(theirs, options());
  FusedAdamW resumed(again, options());
  for (auto* opt : std::initializer_list<torch::optim::Optimizer*>{&reference, &resumed}) {
    std::stringstream copy(saved.str());
    torch::serialize::InputArchive archive;
    archive.load_from(copy);
    opt->load(archive);
  }
  for (int step = 3; step < 6; ++step) {
    set_gradients(ours, step);
    set_gradients(theirs, step);
    set_gradients(again, step);
    fused.step();
    reference.step();
    resumed.step();
  }
  for (size_t k = 0; k < ours.size(); ++k) {
    INFO("parameter " << k);
    CHECK(torch::equal(again[k], ours[k]));  // resuming ours is exact
    CHECK(max_relative(theirs[k], ours[k]) < 1e-6);
  }
}

TEST_CASE("fused AdamW: amsgrad and a non-contiguous parameter take LibTorch's operations, with the same result",
          "[train][optim]") {
  torch::manual_seed(3);
  const torch::Tensor base = torch::randn({8, 6});
  auto make = [&] { return base.t().clone().set_requires_grad(true); };  // .t().clone() keeps the transposed strides
  std::vector<torch::Tensor> ours{make()}, theirs{make()};
  REQUIRE_FALSE(ours[0].is_contiguous());
  FusedAdamW fused(ours, options().amsgrad(true));
  torch::optim::AdamW reference(theirs, options().amsgrad(true));
  for (int step = 0; step < 5; ++step) {
    torch::manual_seed(step);
    const torch::Tensor g = torch::randn_like(ours[0]);
    ours[0].mutable_grad() = g.clone();
    theirs[0].mutable_grad() = g.clone();
    fused.step();
    reference.step();
  }
  CHECK(torch::equal(ours[0], theirs[0]));
}

}  // namespace isplat::fused_adamw_test
