// The DINO branch: a ViT following DINOv3 (patch 16, axial RoPE, register tokens, LayerScale, masked
// K bias) with the official parameter names, so released safetensors checkpoints load directly.
#pragma once
#include <string>

#include <torch/nn/module.h>
#include <torch/nn/modules/container/modulelist.h>
#include <torch/nn/modules/conv.h>
#include <torch/nn/modules/linear.h>
#include <torch/nn/modules/normalization.h>
#include <torch/nn/pimpl.h>

namespace isplat {

class ConfigVisitor;

struct ViTOptions {
  std::string size = "S";  // S | B | L | custom
  int64_t embed_dim = 0;   // custom only (0 = from size)
  int64_t depth = 0;
  int64_t heads = 0;
  int64_t registers = 4;  // DINOv3 "storage tokens"
  double layerscale_init = 1e-5;
  double rope_base = 100.0;
  std::string weights;               // safetensors checkpoint under official DINOv3 names; empty = train from scratch
  int64_t attention_chunk_mb = 256;  // inference: attention scores computed in blocks of at most this size
  void visit(ConfigVisitor& v);
  // Resolved architecture.
  int64_t dim() const;
  int64_t blocks() const;
  int64_t num_heads() const;
};

struct LayerScaleImpl : torch::nn::Module {
  explicit LayerScaleImpl(int64_t dim, double init);
  torch::Tensor forward(const torch::Tensor& x) { return x * gamma; }
  torch::Tensor gamma;
};
TORCH_MODULE(LayerScale);

struct AttentionImpl : torch::nn::Module {
  AttentionImpl(int64_t dim, int64_t heads, int64_t chunk_mb = 256);
  // x [B,N,C]; sin/cos [P,Dh] for the last P (patch) tokens. Without autograd, the scores are computed in
  // blocks of query rows (at most chunk_mb each) and normalized in place: same result, bounded memory.
  torch::Tensor forward(const torch::Tensor& x, const torch::Tensor& sin, const torch::Tensor& cos);
  torch::nn::Linear qkv{nullptr}, proj{nullptr};
  torch::Tensor bias_mask;  // buffer "qkv.bias_mask": zeroes the K part of the qkv bias
  int64_t heads, chunk_mb;
};
TORCH_MODULE(Attention);

struct MlpImpl : torch::nn::Module {
  MlpImpl(int64_t dim, int64_t hidden);
  torch::Tensor forward(const torch::Tensor& x);
  torch::nn::Linear fc1{nullptr}, fc2{nullptr};
};
TORCH_MODULE(Mlp);

struct ViTBlockImpl : torch::nn::Module {
  ViTBlockImpl(int64_t dim, int64_t heads, double layerscale_init, int64_t attention_chunk_mb = 256);
  torch::Tensor forward(const torch::Tensor& x, const torch::Tensor& sin, const torch::Tensor& cos);
  torch::nn::LayerNorm norm1{nullptr}, norm2{nullptr};
  Attention attn{nullptr};
  LayerScale ls1{nullptr}, ls2{nullptr};
  Mlp mlp{nullptr};
};
TORCH_MODULE(ViTBlock);

struct PatchEmbedImpl : torch::nn::Module {
  PatchEmbedImpl(int64_t dim, int64_t patch);
  torch::nn::Conv2d proj{nullptr};
};
TORCH_MODULE(PatchEmbed);

struct RopeEmbedImpl : torch::nn::Module {
  RopeEmbedImpl(int64_t head_dim, double base);
  // (sin, cos) [H*W, head_dim] for an H x W patch grid, DINOv3's "separate" coordinate normalization.
  std::pair<torch::Tensor, torch::Tensor> forward(int64_t H, int64_t W);
  torch::Tensor periods;
};
TORCH_MODULE(RopeEmbed);

struct DinoViTImpl : torch::nn::Module {
  explicit DinoViTImpl(const ViTOptions& options);
  // image [B,3,H,W] sRGB in [0,1], H and W multiples of 16 -> last-layer patch tokens [B,C,H/16,W/16].
  torch::Tensor forward(const torch::Tensor& image);
  int64_t dim() const { return dim_; }

  PatchEmbed patch_embed{nullptr};
  RopeEmbed rope_embed{nullptr};
  torch::nn::ModuleList blocks{nullptr};
  torch::nn::LayerNorm norm{nullptr};
  torch::Tensor cls_token, storage_tokens, mask_token;

 private:
  int64_t dim_, registers_;
};
TORCH_MODULE(DinoViT);

// Loads a safetensors file holding parameters under the official DINOv3 names (e.g. "blocks.0.attn.qkv.weight").
// Missing keys, unexpected keys and shape mismatches are listed together in one Error.
void load_dinov3_safetensors(DinoViT& vit, const std::string& path);

}  // namespace isplat
