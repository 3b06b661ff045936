// Runs an exported ONNX graph in ONNX Runtime (the npm package onnxruntime-node, through node) so its
// output can be compared with LibTorch. OpenCV's DNN module cannot run GridSample, so it is no option.
#pragma once
#include <optional>
#include <string>

#include <torch/types.h>

namespace isplat {

// Where the runner script (scripts/ort_run.js) and the onnxruntime-node package are.
struct OrtRunner {
  std::string script;   // the node script that runs a graph on raw float32 files
  std::string package;  // the onnxruntime-node package folder (holds package.json)
};

// The runner for an installed tool: ISPLAT_ORT_SCRIPT and ISPLAT_ORT_NODE when set, otherwise
// scripts/ort_run.js and third_party/onnxruntime-node/node_modules/onnxruntime-node found by
// resolve_shipped_path (the working directory, then the folders above the executable).
OrtRunner find_ort_runner();
// The runner of a checkout at `root` (tests and benchmarks know their source tree).
OrtRunner ort_runner_in(const std::string& root);

// Returns the graph's "delta" for (image [1,3,H,W], uv [N,2]), or nullopt with `why` set when node,
// the script or onnxruntime-node is missing (scripts/setup.sh installs it). Runtime failures throw Error.
std::optional<torch::Tensor> run_onnxruntime(const std::string& onnx_path, const torch::Tensor& image,
                                             const torch::Tensor& uv, const OrtRunner& runner, std::string& why);

}  // namespace isplat
