// Runs an exported ONNX graph in ONNX Runtime (the npm package onnxruntime-node, through node) so its
// output can be compared with LibTorch. OpenCV's DNN module cannot run GridSample, so it is no option.
#pragma once
#include <optional>
#include <string>

#include <torch/types.h>

namespace isplat {

// Returns the graph's "delta" for (image [1,3,H,W], uv [N,2]), or nullopt with `why` set when node or
// onnxruntime-node is not installed (scripts/setup.sh installs it). Runtime failures throw Error.
std::optional<torch::Tensor> run_onnxruntime(const std::string& onnx_path, const torch::Tensor& image,
                                             const torch::Tensor& uv, std::string& why);

}  // namespace isplat
