// runtime.precision: names and errors, the autocast regions, and the model in bf16 against fp32 (forward and
// gradients within stated tolerances; fp32 unchanged).
#include <catch2/catch.hpp>

#include <torch/torch.h>

#include <cmath>
#include <cstdlib>
#include <map>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "core/precision.h"
#include "data/synth/generate.h"
#include "eval/evaluator.h"
#include "geometry/camera_torch.h"
#include "model/infinisplat.h"
#include "render/render.h"
#include "support/test_util.h"
#include "support/tiny_dataset.h"
#include "support/tiny_model.h"
#include "train/trainer.h"

namespace isplat::precision_test {

constexpr int64_t H = 32, W = 48;

double relative_error(const torch::Tensor& a, const torch::Tensor& reference) {
  return (a - reference).norm().item<double>() / reference.norm().item<double>();
}

double cosine(const torch::Tensor& a, const torch::Tensor& b) {
  return (a * b).sum().item<double>() / (a.norm().item<double>() * b.norm().item<double>());
}

struct Scene {
  torch::Tensor image = torch::rand({3, H, W}), depth = torch::full({H, W}, 2.5f), valid = torch::ones({H, W});
  Camera source{make_K(40, 40, W / 2.0, H / 2.0), torch::eye(4), W, H};
};

// The paper's layout with the implicit decoder, or the default's with the dense head.
InfiniSplat trained_looking_model(bool default_model = false) {
  torch::manual_seed(3);
  InfiniSplat model(default_model ? test::tiny_default_options() : test::tiny_model_options());
  torch::NoGradGuard g;  // the zero-initialized head would make every update 0 in both precisions
  (default_model ? model->dense->out->weight : model->decoder->head->weight).normal_(0, 0.1);
  return model;
}

TEST_CASE("precision: names resolve, auto follows the CPU, anything else is refused naming the key", "[precision]") {
  CHECK(resolve_precision("fp32") == Precision::fp32);
  CHECK(resolve_precision("bf16") == Precision::bf16);
  CHECK(resolve_precision("auto") == (cpu_has_bf16() ? Precision::bf16 : Precision::fp32));
  CHECK_THROWS_WITH(resolve_precision("fp16", "--precision"),
                    Catch::Contains("--precision") && Catch::Contains("fp16") && Catch::Contains("fp32, bf16 or auto"));
  CHECK(std::string(precision_name(Precision::bf16)) == "bf16");
}

TEST_CASE("precision: a oneDNN ISA cap below its bf16 kernels turns auto to fp32, and bf16 is refused where it fails",
          "[precision]") {
  CHECK(onednn_bf16_under_cap("AVX2") == OnednnBf16::none);
  CHECK(onednn_bf16_under_cap("avx2_vnni") == OnednnBf16::none);
  CHECK(onednn_bf16_under_cap("AVX512_CORE") == OnednnBf16::emulated);
  CHECK(onednn_bf16_under_cap("avx512_core_vnni") == OnednnBf16::emulated);
  CHECK(onednn_bf16_under_cap("AVX512_CORE_BF16") == OnednnBf16::native);
  CHECK(onednn_bf16_under_cap("avx512_core_amx") == OnednnBf16::native);
  CHECK(onednn_bf16_under_cap("ALL") == OnednnBf16::native);
  // The cap is read at each call; the test leaves the environment as it found it.
  const test::ScopedEnv onednn("ONEDNN_MAX_CPU_ISA", nullptr), dnnl("DNNL_MAX_CPU_ISA", "AVX2");
  CHECK(onednn_bf16_cap() == "DNNL_MAX_CPU_ISA=AVX2");
  CHECK_FALSE(cpu_has_bf16());
  CHECK(resolve_precision("auto") == Precision::fp32);
  setenv("ONEDNN_MAX_CPU_ISA", "AVX512_CORE_AMX", 1);  // the newer name wins
  CHECK(onednn_bf16_cap().empty());
  setenv("ONEDNN_MAX_CPU_ISA", "avx512_core", 1);  // emulated: auto stays fp32, an explicit bf16 runs
  CHECK(onednn_bf16_cap() == "ONEDNN_MAX_CPU_ISA=avx512_core");
  CHECK(resolve_precision("auto") == Precision::fp32);
  CHECK(resolve_precision("bf16") == Precision::bf16);
  // Capped at AVX2: on an AVX-512 CPU LibTorch would send bf16 matmuls to a oneDNN without bf16 kernels, so bf16 is
  // refused, naming the variable, and the process-wide precision stays as it was; elsewhere bf16 runs LibTorch's loops.
  const PrecisionScope keep(Precision::fp32);
  setenv("ONEDNN_MAX_CPU_ISA", "AVX2", 1);
  if (cpu_sends_bf16_to_onednn()) {
    CHECK_THROWS_WITH(use_precision("bf16", "--precision"),
                      Catch::Contains("--precision") && Catch::Contains("ONEDNN_MAX_CPU_ISA=AVX2"));
    CHECK(compute_precision() == Precision::fp32);
  } else {
    CHECK_NOTHROW(use_precision("bf16", "--precision"));
    CHECK(compute_precision() == Precision::bf16);
  }
}

TEST_CASE("precision: a bf16 region casts matmuls and restores the state it found, nested or not", "[precision]") {
  const auto a = torch::rand({8, 16}), b = torch::rand({16, 4});
  CHECK(torch::matmul(a, b).scalar_type() == torch::kFloat32);
  {
    const Bf16Region outer(true);
    CHECK(torch::matmul(a, b).scalar_type() == torch::kBFloat16);
    {
      const Bf16Region inner(true);
      CHECK(torch::matmul(a, b).scalar_type() == torch::kBFloat16);
      const Fp32Region plain;
      CHECK(torch::matmul(a, b).scalar_type() == torch::kFloat32);
    }
    CHECK(torch::matmul(a, b).scalar_type() == torch::kBFloat16);
    CHECK((a + a).scalar_type() == torch::kFloat32);  // elementwise work keeps its type
  }
  CHECK(torch::matmul(a, b).scalar_type() == torch::kFloat32);
  const Bf16Region off(false);
  CHECK(torch::matmul(a, b).scalar_type() == torch::kFloat32);
}

TEST_CASE("precision: a weight changed between bf16 regions is seen (the cast cache ends with the region)",
          "[precision]") {
  auto w = torch::ones({4, 4}, torch::requires_grad());
  const auto x = torch::ones({1, 4});
  double before = 0, after = 0;
  {
    const Bf16Region r(true);
    before = torch::nn::functional::linear(x, w).sum().item<double>();
  }
  {
    torch::NoGradGuard g;
    w.mul_(2);  // an optimizer step
  }
  {
    const Bf16Region r(true);
    after = torch::nn::functional::linear(x, w).sum().item<double>();
  }
  CHECK(before == 16.0);
  CHECK(after == 32.0);
}

TEST_CASE("precision: the model in bf16 predicts fp32 Gaussians within 3% of fp32's updates", "[precision][model]") {
  const bool default_model = GENERATE(false, true);
  INFO((default_model ? "the default model (dense head)" : "the paper's layout (implicit decoder)"));
  InfiniSplat model = trained_looking_model(default_model);
  const Scene s;
  const Prediction fp32 = model->predict(s.image, s.source.K, s.source.T_cw, s.depth, s.valid, 1);
  Prediction bf16;
  {
    const PrecisionScope p(Precision::bf16);
    bf16 = model->predict(s.image, s.source.K, s.source.T_cw, s.depth, s.valid, 1);
  }
  const Prediction fp32_again = model->predict(s.image, s.source.K, s.source.T_cw, s.depth, s.valid, 1);
  CHECK(torch::equal(fp32.delta, fp32_again.delta));  // fp32 after a bf16 run is what it was
  CHECK(bf16.delta.scalar_type() == torch::kFloat32);
  CHECK(bf16.gaussians.means.scalar_type() == torch::kFloat32);
  CHECK(torch::equal(bf16.supports.uv, fp32.supports.uv));  // the sampler is not touched
  const double err = relative_error(bf16.delta, fp32.delta);
  INFO("relative error of the updates " << err);
  CHECK(err > 0);  // bf16 really ran
  CHECK(err < 0.03);
}

TEST_CASE("precision: training in bf16 keeps fp32 weights and gradients that point where fp32's do",
          "[precision][model]") {
  torch::manual_seed(5);  // the scene: the same in a batch run and in ctest's one process per test
  const Scene s;
  const Camera target{s.source.K,
                      [] {
                        auto T = torch::eye(4);
                        T[0][3] = 0.2;
                        return T;
                      }(),
                      W, H};
  auto gradients = [&](Precision precision) {
    InfiniSplat model = trained_looking_model();
    const PrecisionScope p(precision);
    Prediction pred = model->forward(s.image, s.source.K, s.source.T_cw, s.depth, s.valid, 1);
    render(pred.gaussians, target).rgb.mean().backward();
    std::map<std::string, torch::Tensor> g;
    for (const auto& item : model->named_parameters()) {
      CHECK(item.value().scalar_type() == torch::kFloat32);
      if (item.value().grad().defined()) g[item.key()] = item.value().grad().clone();
    }
    return g;
  };
  const auto fp32 = gradients(Precision::fp32), bf16 = gradients(Precision::bf16);
  REQUIRE(fp32.size() == bf16.size());
  // Layer by layer where the gradient is a sum over few terms. The CNN's first layer sums bf16 values over every
  // pixel with much cancellation (its cosine read 0.91-0.97 on different scenes) and has the largest gradient, so it
  // is checked in the whole, which it dominates (0.989 on this scene): same direction, within 0.02.
  std::vector<torch::Tensor> all_fp32, all_bf16;
  for (const auto& [name, g] : fp32) {
    REQUIRE(bf16.count(name) == 1);
    CHECK(bf16.at(name).scalar_type() == torch::kFloat32);
    CHECK(torch::isfinite(bf16.at(name)).all().item<bool>());
    all_fp32.push_back(g.flatten()), all_bf16.push_back(bf16.at(name).flatten());
  }
  for (const char* name :
       {"encoder.vit.blocks.0.attn.qkv.weight", "decoder.gate.weight", "decoder.mlp.0.weight", "decoder.head.weight"}) {
    INFO(name << ": cosine " << cosine(bf16.at(name), fp32.at(name)));
    CHECK(cosine(bf16.at(name), fp32.at(name)) > 0.99);
  }
  const double whole = cosine(torch::cat(all_bf16), torch::cat(all_fp32));
  INFO("all parameters: cosine " << whole);
  CHECK(whole > 0.98);
}

}  // namespace isplat::precision_test

namespace isplat::precision_eval_test {

TEST_CASE("precision: the evaluator scores one checkpoint in fp32 and bf16 on the same pairs, stamped as run",
          "[precision][eval]") {
  test::QuietLogs quiet;
  const auto g = test::make_tiny_dataset("precision_eval", 16);
  const std::string ck = test::temp_dir("precision_eval_ck") + "/tiny.safetensors";
  {
    Trainer trainer(test::tiny_train_config(g, test::temp_dir("precision_eval_run"), 3));
    for (int i = 0; i < 3; ++i) trainer.train_step();  // a head that is no longer zero: bf16 changes the updates
    trainer.save(ck);
  }
  EvalConfig c;
  EvalDatasetOptions d;
  d.name = "courtyard", d.format = "colmap", d.root = generated_eval_root(g.out, "courtyard_colmap");
  c.datasets = {d};
  c.methods.push_back(named_method("fp32", "model", ck, {"prior.type=dataset"}));
  c.methods.push_back(named_method("bf16", "model", ck, {"prior.type=dataset"}));
  c.methods.back().precision = "bf16";
  c.protocol.pairs_per_bin = 2;
  c.scoring.out = test::temp_dir("precision_eval_out");
  c.scoring.lpips = {};
  c.scoring.examples = 0;
  const auto rows = Evaluator(c).run();
  std::map<std::string, const ReportRow*> all;
  for (const auto& r : rows)
    if (r.bin == "all") all[r.method.label()] = &r;
  REQUIRE(all.count("fp32") == 1);
  REQUIRE(all.count("bf16") == 1);
  CHECK(all["fp32"]->pairs == all["bf16"]->pairs);
  CHECK(all["bf16"]->psnr != all["fp32"]->psnr);  // bf16 really ran
  CHECK(std::fabs(all["bf16"]->psnr - all["fp32"]->psnr) < 0.2);
  auto stamp = [&](const std::string& method) {
    return nlohmann::json::parse(
        test::read_bytes(c.scoring.out + "/courtyard/results_" + method + ".jsonl.method.json"));
  };
  CHECK(stamp("fp32").at("precision") == "fp32");
  CHECK(stamp("bf16").at("precision") == "bf16");
  // Resuming with the other precision would mix scores: refused, naming the method.
  for (auto& m : c.methods)  // the config's methods: the default baselines (lift, identity), then ours
    if (m.name == "fp32") m.precision = "bf16";
  CHECK_THROWS_WITH(Evaluator(c).run(), Catch::Contains("other options") && Catch::Contains("'fp32'"));
  // A method that runs no network has no precision to choose.
  c.methods = {named_method("lift", "lift")};
  c.methods.front().precision = "bf16";
  CHECK_THROWS_WITH(Evaluator(c).run(), Catch::Contains("'lift'") && Catch::Contains("type model only"));
}

}  // namespace isplat::precision_eval_test

namespace isplat::precision_train_test {

TEST_CASE("precision: a trainer runs in its own runtime.precision, whatever the process's, and restores it",
          "[precision][train]") {
  test::QuietLogs quiet;
  const auto g = test::make_tiny_dataset("precision_train", 16);
  auto first_steps = [&](const std::string& precision) {
    TrainConfig config = test::tiny_train_config(g, test::temp_dir("precision_train_" + precision), 3);
    config.runtime.precision = precision;
    Trainer trainer(config);
    std::vector<double> losses;
    for (int i = 0; i < 3; ++i) losses.push_back(trainer.train_step().losses.at("total"));
    return losses;
  };
  REQUIRE(compute_precision() == Precision::fp32);  // as an experiment's process is: its rows set their own
  const auto fp32 = first_steps("fp32"), bf16 = first_steps("bf16");
  CHECK(compute_precision() == Precision::fp32);
  CHECK(fp32 == first_steps("fp32"));  // deterministic, so a difference below is the precision's
  CHECK(bf16 != fp32);
  for (size_t i = 0; i < fp32.size(); ++i) CHECK(bf16[i] == Approx(fp32[i]).epsilon(0.05));
}

}  // namespace isplat::precision_train_test
