// The table of subcommands.
#include "cli/commands.h"

namespace isplat::cli {

std::map<std::string, Command> all_commands() {
  return {
      {"version", {"print versions, threads, BLAS and a matmul speed check", run_version}},
      {"generate", {"render the synthetic datasets (Hypersim layout + COLMAP/nerfstudio eval sets)", run_generate}},
      {"predict", {"one photograph -> Gaussians (3DGS PLY) with a trained checkpoint", run_predict}},
      {"export", {"a PLY scene as .splat, .spz, PLY with SH degree 3, or a self-contained HTML viewer", run_export}},
      {"export-onnx",
       {"a checkpoint's encoder + decoder (dense head or implicit) as an ONNX graph (opset 17)", run_export_onnx}},
      {"render", {"novel views of a PLY: orbit, dolly or a camera path, as PNG frames and MP4", run_render}},
      {"eval-depth",
       {"AbsRel and delta<1.25 of depth priors against datasets' depth, per depth range", run_eval_depth}},
      {"weights", {"where the pretrained weights are looked for, and which were found", run_weights}},
  };
}

}  // namespace isplat::cli
