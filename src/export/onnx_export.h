// ONNX export of the learned part of the model, built with the ONNX protobuf API: the encoder (ViT +
// CNN) and the decoder (dense head or implicit) as one graph, image + support coordinates in, 14-dim updates out.
#pragma once
#include <string>

#include "model/infinisplat.h"

namespace onnx {
class ModelProto;
}

namespace isplat {

struct OnnxExportOptions {
  int64_t width = 256, height = 192;  // fixed image size (multiples of 16); supports are dynamic
  int64_t opset = 17;                 // >= 17 for LayerNormalization; GridSample needs >= 16
};

// Graph inputs: "image" [1,3,H,W] sRGB in [0,1], "uv" [N,2] pixel coordinates. Output: "delta" [N,14].
// Every module type in the model must have an export rule; otherwise Error names the layer.
onnx::ModelProto export_onnx(InfiniSplat& model, const OnnxExportOptions& options);

// Runs onnx::checker::check_model and writes the file atomically. Returns the byte size.
int64_t save_onnx(const onnx::ModelProto& model, const std::string& path);

}  // namespace isplat
