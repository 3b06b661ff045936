// DINOv3-style ViT: patch embedding, cls + register tokens, blocks with axial RoPE and LayerScale.
#include "encoder/vit.h"

#include <torch/torch.h>

#include <cmath>
#include <set>

#include "core/config.h"
#include "core/error.h"
#include "io/checkpoint.h"
#include "io/safetensors.h"
#include "nets/imagenet.h"

namespace isplat {
namespace nn = torch::nn;

void ViTOptions::visit(ConfigVisitor& v) {
  v.field("size", size, "ViT size: S (384-d, 12 blocks), B (768, 12), L (1024, 24; paper), or custom",
          {"S", "B", "L", "custom"});
  v.field("embed_dim", embed_dim, "custom size: token width (multiple of 4 x heads)", Range::between(0, 4096));
  v.field("depth", depth, "custom size: number of blocks", Range::between(0, 64));
  v.field("heads", heads, "custom size: attention heads", Range::between(0, 64));
  v.field("registers", registers, "register (storage) tokens; DINOv3 uses 4", Range::between(0, 64));
  v.field("layerscale_init", layerscale_init, "LayerScale initial gamma", Range::above(0));
  v.field("rope_base", rope_base, "RoPE period base", Range::above(1));
  v.field("weights", weights,
          "DINOv3 safetensors checkpoint (official names), from its publisher: a file name is looked up like the "
          "other weights ($INFINISPLAT_WEIGHTS, the checkout's weights/, ~/.cache/infinisplat/weights), a path is "
          "taken as given; empty = train from scratch");
  v.field("attention_chunk_mb", attention_chunk_mb,
          "inference only: attention scores are computed in blocks of query rows of at most this many MB "
          "(bounds memory at large images; same result)",
          Range::between(1, 1 << 20));
}

namespace {
struct ViTPreset {
  const char* size;
  int64_t dim, blocks, heads;
};
constexpr ViTPreset kViTPresets[] = {{"S", 384, 12, 6}, {"B", 768, 12, 12}, {"L", 1024, 24, 16}};

const ViTPreset* vit_preset(const std::string& size) {
  for (const auto& p : kViTPresets)
    if (size == p.size) return &p;
  return nullptr;  // custom
}
}  // namespace

int64_t ViTOptions::dim() const {
  if (const ViTPreset* p = vit_preset(size)) return p->dim;
  ISPLAT_CHECK(embed_dim > 0, "encoder.vit.size = custom needs encoder.vit.embed_dim");
  return embed_dim;
}
int64_t ViTOptions::blocks() const {
  if (const ViTPreset* p = vit_preset(size)) return p->blocks;
  ISPLAT_CHECK(depth > 0, "encoder.vit.size = custom needs encoder.vit.depth");
  return depth;
}
int64_t ViTOptions::num_heads() const {
  if (const ViTPreset* p = vit_preset(size)) return p->heads;
  ISPLAT_CHECK(heads > 0, "encoder.vit.size = custom needs encoder.vit.heads");
  return heads;
}

LayerScaleImpl::LayerScaleImpl(int64_t dim, double init) {
  gamma = register_parameter("gamma", torch::full({dim}, init));
}

AttentionImpl::AttentionImpl(int64_t dim, int64_t h, int64_t chunk) : heads(h), chunk_mb(chunk) {
  qkv = register_module("qkv", nn::Linear(nn::LinearOptions(dim, 3 * dim).bias(true)));
  // DINOv3 masks the K part of the qkv bias (LinearKMaskedBias); the mask is a checkpoint buffer.
  auto mask = torch::ones({3 * dim});
  mask.narrow(0, dim, dim).zero_();
  bias_mask = qkv->register_buffer("bias_mask", mask);
  proj = register_module("proj", nn::Linear(dim, dim));
}

namespace {
torch::Tensor rotate_half(const torch::Tensor& x) {
  auto halves = x.chunk(2, -1);
  return torch::cat({-halves[1], halves[0]}, -1);
}
}  // namespace

torch::Tensor AttentionImpl::forward(const torch::Tensor& x, const torch::Tensor& sin, const torch::Tensor& cos) {
  const int64_t B = x.size(0), N = x.size(1), C = x.size(2), Dh = C / heads;
  auto bias = qkv->bias * bias_mask;
  auto t = torch::nn::functional::linear(x, qkv->weight, bias).reshape({B, N, 3, heads, Dh}).permute({2, 0, 3, 1, 4});
  auto q = t[0], k = t[1], v = t[2];  // [B,h,N,Dh]
  const int64_t P = sin.size(0), prefix = N - P;
  auto rope = [&](const torch::Tensor& z) {
    auto patch = z.narrow(2, prefix, P);
    return torch::cat({z.narrow(2, 0, prefix), patch * cos + rotate_half(patch) * sin}, 2);
  };
  q = rope(q);
  k = rope(k);
  const double scale = 1.0 / std::sqrt(static_cast<double>(Dh));
  torch::Tensor out;
  if (torch::GradMode::is_enabled()) {
    out = torch::matmul(torch::softmax(torch::matmul(q, k.transpose(-2, -1)) * scale, -1), v);
  } else {
    const auto kt = k.transpose(-2, -1);
    q = q * scale;
    out = torch::empty_like(q);
    const int64_t bytes_per_row = B * heads * N * static_cast<int64_t>(sizeof(float));
    const int64_t rows = std::max<int64_t>(1, (chunk_mb << 20) / std::max<int64_t>(1, bytes_per_row));
    for (int64_t s = 0; s < N; s += rows) {
      const int64_t n = std::min(rows, N - s);
      auto scores = torch::matmul(q.narrow(2, s, n), kt);
      if (scores.scalar_type() == torch::kBFloat16) {
        // bf16 scores (runtime.precision): the softmax in fp32 in one fused pass; elementwise bf16 is slow here.
        scores = torch::softmax(scores, -1, torch::kFloat);
      } else {
        scores.sub_(std::get<0>(scores.max(-1, true))).exp_();
        scores.div_(scores.sum(-1, true));
      }
      out.narrow(2, s, n).copy_(torch::matmul(scores, v));
    }
  }
  return proj->forward(out.transpose(1, 2).reshape({B, N, C}));
}

MlpImpl::MlpImpl(int64_t dim, int64_t hidden) {
  fc1 = register_module("fc1", nn::Linear(dim, hidden));
  fc2 = register_module("fc2", nn::Linear(hidden, dim));
}

torch::Tensor MlpImpl::forward(const torch::Tensor& x) {
  return fc2->forward(torch::gelu(fc1->forward(x)));
}

ViTBlockImpl::ViTBlockImpl(int64_t dim, int64_t heads, double ls, int64_t chunk_mb) {
  norm1 = register_module("norm1", nn::LayerNorm(nn::LayerNormOptions({dim}).eps(1e-5)));
  attn = register_module("attn", Attention(dim, heads, chunk_mb));
  ls1 = register_module("ls1", LayerScale(dim, ls));
  norm2 = register_module("norm2", nn::LayerNorm(nn::LayerNormOptions({dim}).eps(1e-5)));
  mlp = register_module("mlp", Mlp(dim, 4 * dim));
  ls2 = register_module("ls2", LayerScale(dim, ls));
}

torch::Tensor ViTBlockImpl::forward(const torch::Tensor& x, const torch::Tensor& sin, const torch::Tensor& cos) {
  auto h = x + ls1->forward(attn->forward(norm1->forward(x), sin, cos));
  return h + ls2->forward(mlp->forward(norm2->forward(h)));
}

PatchEmbedImpl::PatchEmbedImpl(int64_t dim, int64_t patch) {
  proj = register_module("proj", nn::Conv2d(nn::Conv2dOptions(3, dim, patch).stride(patch)));
}

RopeEmbedImpl::RopeEmbedImpl(int64_t head_dim, double base) {
  ISPLAT_CHECK(head_dim % 4 == 0, "ViT: head dimension ", head_dim, " must be a multiple of 4 for axial RoPE");
  const int64_t n = head_dim / 4;
  periods = register_buffer("periods", torch::pow(base, 2.0 * torch::arange(n, torch::kFloat32) / (head_dim / 2)));
}

std::pair<torch::Tensor, torch::Tensor> RopeEmbedImpl::forward(int64_t H, int64_t W) {
  auto ch = (torch::arange(H, torch::kFloat32) + 0.5) / H;
  auto cw = (torch::arange(W, torch::kFloat32) + 0.5) / W;
  auto grid = torch::meshgrid({ch, cw}, "ij");
  auto coords = torch::stack({grid[0], grid[1]}, -1).reshape({H * W, 2}) * 2.0 - 1.0;  // [P,2]
  auto angles = 2.0 * M_PI * coords.unsqueeze(-1) / periods.view({1, 1, -1});          // [P,2,D/4]
  angles = angles.flatten(1, 2).repeat({1, 2});                                        // [P,D]
  return {torch::sin(angles), torch::cos(angles)};
}

DinoViTImpl::DinoViTImpl(const ViTOptions& o) : dim_(o.dim()), registers_(o.registers) {
  const int64_t heads = o.num_heads();
  ISPLAT_CHECK(dim_ % (4 * heads) == 0, "ViT: embed_dim ", dim_, " must be a multiple of 4 x heads (", 4 * heads, ")");
  patch_embed = register_module("patch_embed", PatchEmbed(dim_, 16));
  cls_token = register_parameter("cls_token", torch::randn({1, 1, dim_}) * 0.02);
  if (registers_ > 0) storage_tokens = register_parameter("storage_tokens", torch::randn({1, registers_, dim_}) * 0.02);
  mask_token = register_parameter("mask_token", torch::zeros({1, dim_}));
  rope_embed = register_module("rope_embed", RopeEmbed(dim_ / heads, o.rope_base));
  blocks = register_module("blocks", nn::ModuleList());
  for (int64_t i = 0; i < o.blocks(); ++i)
    blocks->push_back(ViTBlock(dim_, heads, o.layerscale_init, o.attention_chunk_mb));
  norm = register_module("norm", nn::LayerNorm(nn::LayerNormOptions({dim_}).eps(1e-5)));
  // DINOv3 initialization: truncated normal linears, zero biases.
  for (auto& m : modules(false))
    if (auto* lin = m->as<nn::Linear>()) {
      torch::NoGradGuard g;
      lin->weight.normal_(0.0, 0.02).clamp_(-0.04, 0.04);  // truncated at 2 std
      lin->bias.zero_();
    }
}

torch::Tensor DinoViTImpl::forward(const torch::Tensor& image) {
  ISPLAT_CHECK(image.dim() == 4 && image.size(1) == 3, "ViT: image must be [B, 3, H, W], got ", image.sizes());
  ISPLAT_CHECK(image.size(2) >= 16 && image.size(3) >= 16 && image.size(2) % 16 == 0 && image.size(3) % 16 == 0,
               "ViT: image size ", image.size(3), "x", image.size(2), " must be a multiple of the 16-px patch");
  auto x = patch_embed->proj->forward(imagenet_normalize(image));  // [B,C,h,w]
  const int64_t B = x.size(0), h = x.size(2), w = x.size(3);
  x = x.flatten(2).transpose(1, 2);  // [B,h*w,C]
  std::vector<torch::Tensor> parts = {(cls_token + 0 * mask_token.unsqueeze(0)).expand({B, 1, dim_})};
  if (registers_ > 0) parts.push_back(storage_tokens.expand({B, registers_, dim_}));
  parts.push_back(x);
  x = torch::cat(parts, 1);
  auto [sin, cos] = rope_embed->forward(h, w);
  sin = sin.to(x.dtype());
  cos = cos.to(x.dtype());
  for (auto& blk : *blocks) x = blk->as<ViTBlock>()->forward(x, sin, cos);
  x = norm->forward(x);
  return x.narrow(1, 1 + registers_, h * w).transpose(1, 2).reshape({B, dim_, h, w});
}

void load_dinov3_safetensors(DinoViT& vit, const std::string& path) {
  // Present in some official checkpoints but unused at inference (untied cls norms).
  auto ignorable = [](const std::string& k) {
    return k.rfind("local_cls_norm.", 0) == 0 || k.rfind("cls_norm.", 0) == 0;
  };
  load_named_tensors(*vit, read_safetensors(path).tensors, "",
                     path + ": does not fit this ViT (encoder.vit.size/registers must match the checkpoint).",
                     ignorable);
}

}  // namespace isplat
