// `infinisplat export-onnx`: the encoder + decoder (dense head or implicit) of a checkpoint as an ONNX graph.
#include <onnx/onnx_pb.h>

#include <filesystem>
#include <iostream>

#include <torch/torch.h>

#include "cli/commands.h"
#include "core/args.h"
#include "core/error.h"
#include "core/runtime.h"
#include "export/onnx_export.h"
#include "export/onnx_runtime_check.h"
#include "model/model_io.h"

namespace isplat::cli {

int run_export_onnx(int argc, char** argv) {
  std::string checkpoint, out;
  int64_t width = 256, height = 192, opset = 17, threads = 0;
  bool verify = false;
  ArgParser args("infinisplat export-onnx",
                 "Write the encoder (ViT + CNN) and the decoder (dense head or implicit) of a checkpoint as "
                 "one ONNX graph: inputs image [1,3,H,W] and uv [N,2], output delta [N,14]. "
                 "Weights are initializers; the graph passes onnx::checker.");
  args.option("--checkpoint", checkpoint, "trained checkpoint", "FILE");
  args.option("--out", out, "output .onnx file", "FILE");
  args.option("--width", width, "image width the graph takes (multiple of 16)").range(16, 65536, "pixels");
  args.option("--height", height, "image height the graph takes (multiple of 16)").range(16, 65536, "pixels");
  args.option("--opset", opset, "ONNX opset (>= 17)").range(17, 100);
  args.flag("--verify", verify, "run the graph in ONNX Runtime (onnxruntime-node) and compare with LibTorch");
  args.option("--threads", threads, "threads (0 = all cores)").range(0, kMaxThreads);
  if (!args.parse(argc, argv, 2)) return 0;
  ISPLAT_CHECK(!checkpoint.empty() && !out.empty(), "export-onnx: --checkpoint and --out are required (see --help)");
  ISPLAT_CHECK(width % 16 == 0 && height % 16 == 0 && width <= max_image_pixels() / height, "export-onnx: --width ",
               width, " x --height ", height, " must be multiples of 16 within runtime.max_image_pixels (",
               max_image_pixels(), ")");
  configure_threads(threads);
  ErrorContext context("exporting ", checkpoint, " to ONNX at ", width, "x", height);
  auto pipeline = load_pipeline(checkpoint);
  auto& model = pipeline->model();
  const onnx::ModelProto mp = export_onnx(model, {width, height, opset});
  const int64_t bytes = save_onnx(mp, out);
  std::cout << "wrote " << std::filesystem::absolute(out).string() << " (" << bytes / 1e6 << " MB, "
            << mp.graph().node_size() << " nodes, " << mp.graph().initializer_size() << " initializers, opset " << opset
            << "); checker passed\n";
  if (verify) {
    torch::manual_seed(0);
    auto image = torch::rand({1, 3, height, width});
    auto uv = torch::rand({2000, 2}) * torch::tensor({float(width), float(height)});
    EncoderFeatures f;
    torch::Tensor expect;
    {
      torch::NoGradGuard g;
      f = model->encoder->forward(image);
      expect = model->decode(f, uv, width, height);
    }
    std::string why;
    const auto got = run_onnxruntime(out, image, uv, find_ort_runner(), why);
    if (!got) {
      std::cout << "verify: skipped, " << why << "\n";
      return 0;
    }
    const double err = (*got - expect).abs().max().item<double>();
    std::cout << "verify: ONNX Runtime vs LibTorch on 2000 supports: max abs error " << err
              << (err <= 1e-4 ? " (ok)" : " (TOO LARGE)") << "\n";
    return err <= 1e-4 ? 0 : 1;
  }
  return 0;
}

}  // namespace isplat::cli
