// ONNX export: the graph passes onnx::checker, ONNX Runtime reproduces LibTorch to 1e-4 (when node and
// onnxruntime-node are installed), every layer needs an export rule, and bad sizes are refused.
#include <catch2/catch.hpp>

#include <onnx/onnx_pb.h>
#include <torch/torch.h>

#include <filesystem>

#include "export/onnx_export.h"
#include "export/onnx_runtime_check.h"
#include "support/test_util.h"
#include "support/tiny_model.h"

using namespace isplat;

namespace {
void randomize_head(InfiniSplat& m) {
  torch::NoGradGuard g;
  if (m->decoder) {
    m->decoder->head->weight.normal_(0, 0.2);
    m->decoder->head->bias.normal_(0, 0.2);
  }
  if (m->dense) {
    m->dense->out->weight.normal_(0, 0.2);
    m->dense->out->bias.normal_(0, 0.2);
  }
}

torch::Tensor reference(InfiniSplat& m, const torch::Tensor& image, const torch::Tensor& uv, int64_t W, int64_t H) {
  torch::NoGradGuard g;
  const auto f = m->encoder->forward(image);
  return m->decode(f, uv, W, H);
}

struct Variant {
  const char* name;
  std::function<void(ModelOptions&)> set;
};

// Each variant exported, checked, and run in ONNX Runtime against LibTorch.
void check_onnx_variants(const std::vector<Variant>& variants) {
  torch::manual_seed(0);
  const int64_t W = 64, H = 48;
  const auto dir = test::temp_dir("onnx");
  for (const auto& v : variants) {
    INFO(v.name);
    ModelOptions o = test::tiny_model_options(600, 2);
    v.set(o);
    InfiniSplat m(o);
    randomize_head(m);
    const onnx::ModelProto mp = export_onnx(m, {W, H, 17});
    CHECK(mp.graph().input_size() == 2);
    CHECK(mp.graph().input(0).name() == "image");
    CHECK(mp.graph().input(1).name() == "uv");
    CHECK(mp.graph().output(0).name() == "delta");
    bool has_grid_sample = false;
    for (const auto& n : mp.graph().node()) has_grid_sample |= n.op_type() == "GridSample";
    CHECK(has_grid_sample);
    const std::string path = dir + "/" + v.name + ".onnx";
    CHECK(save_onnx(mp, path) > 0);  // includes onnx::checker::check_model
    auto image = torch::rand({1, 3, H, W});
    auto uv = torch::rand({500, 2}) * torch::tensor({float(W), float(H)});
    std::string why;
    const auto got = run_onnxruntime(path, image, uv, ort_runner_in(ISPLAT_SOURCE_DIR), why);
    if (!got) {
      WARN("ONNX Runtime comparison skipped: " << why);
      CHECK(!why.empty());
      continue;
    }
    const double err = (*got - reference(m, image, uv, W, H)).abs().max().item<double>();
    INFO("max abs error " << err);
    CHECK(err <= 1e-4);
  }
}
}  // namespace

TEST_CASE("onnx: exported graphs pass the checker and match LibTorch in ONNX Runtime", "[export][onnx]") {
  check_onnx_variants({{"implicit", [](ModelOptions&) {}},
                       {"dense", [](ModelOptions& o) { o.decoder.mode = "dense"; }},
                       {"cnn_only", [](ModelOptions& o) { o.encoder.dino = false; }}});
}

TEST_CASE("onnx: the frozen SqueezeNet semantic branch exports and matches LibTorch", "[export][onnx][weights]") {
  ISPLAT_REQUIRE_WEIGHTS();
  check_onnx_variants({{"squeeze_semantic", [](ModelOptions& o) {
                          o.encoder.semantic = "squeeze";
                          o.encoder.semantic_backbone = test::squeezenet_weights();
                        }}});
}

TEST_CASE("onnx: unsupported layers and sizes are named", "[export][onnx]") {
  InfiniSplat m(test::tiny_model_options(600, 2));
  CHECK_THROWS_WITH(export_onnx(m, {60, 48, 17}), Catch::Contains("must be multiples of 16"));
  CHECK_THROWS_WITH(export_onnx(m, {64, 48, 13}), Catch::Contains("opset 13 is too old"));
  m->register_module("extra", torch::nn::Dropout(0.1));
  CHECK_THROWS_WITH(export_onnx(m, {64, 48, 17}),
                    Catch::Contains("no export rule for layer 'torch::nn::DropoutImpl' (at model.extra)"));
  ModelOptions none = test::tiny_model_options(600, 2);
  none.decoder.mode = "none";
  InfiniSplat n(none);
  CHECK_THROWS_WITH(export_onnx(n, {64, 48, 17}), Catch::Contains("no learned part to export"));
}
