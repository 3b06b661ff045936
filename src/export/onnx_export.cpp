// Export rules per layer type (ViT block, residual CNN block, gated decoder, dense head) emitting ONNX
// nodes with weights as initializers. Shapes follow the LibTorch forward exactly, so outputs agree.
#include "export/onnx_export.h"

#include <onnx/checker.h>
#include <onnx/onnx_pb.h>
#include <torch/torch.h>

#include <set>
#include <variant>

#include "core/error.h"
#include "decoder/composer.h"
#include "io/atomic_file.h"
#include "nets/feature_net.h"
#include "nets/imagenet.h"

namespace isplat {
namespace {

// Small helper that names values and appends nodes and initializers to a graph.
class Graph {
 public:
  explicit Graph(onnx::GraphProto* g) : g_(g) {}

  std::string fresh(const std::string& hint) { return hint + "_" + std::to_string(counter_++); }

  std::string init(const std::string& hint, const torch::Tensor& t_in) {
    const std::string name = fresh(hint);
    auto* tp = g_->add_initializer();
    tp->set_name(name);
    auto t = t_in.detach().contiguous();
    for (int64_t d : t.sizes()) tp->add_dims(d);
    if (t.scalar_type() == torch::kInt64) {
      tp->set_data_type(onnx::TensorProto::INT64);
      tp->set_raw_data(std::string(static_cast<const char*>(t.data_ptr()), t.numel() * 8));
    } else {
      auto f = t.to(torch::kFloat32).contiguous();
      tp->set_data_type(onnx::TensorProto::FLOAT);
      tp->set_raw_data(std::string(static_cast<const char*>(f.data_ptr()), f.numel() * 4));
    }
    return name;
  }
  std::string ints(const std::vector<int64_t>& v) { return init("const", torch::tensor(v, torch::kInt64)); }
  std::string scalar(double v) { return init("const", torch::tensor({static_cast<float>(v)})); }

  struct Attr {
    std::string name;
    enum Kind { Int, Ints, Float, String } kind;
    int64_t i = 0;
    std::vector<int64_t> is;
    float f = 0;
    std::string s;
  };
  static Attr a_int(const std::string& n, int64_t v) { return {n, Attr::Int, v, {}, 0, ""}; }
  static Attr a_ints(const std::string& n, std::vector<int64_t> v) { return {n, Attr::Ints, 0, std::move(v), 0, ""}; }
  static Attr a_float(const std::string& n, float v) { return {n, Attr::Float, 0, {}, v, ""}; }
  static Attr a_str(const std::string& n, const std::string& v) { return {n, Attr::String, 0, {}, 0, v}; }

  std::vector<std::string> op_n(const std::string& type, const std::vector<std::string>& in, int outputs,
                                const std::vector<Attr>& attrs = {}) {
    auto* n = g_->add_node();
    n->set_op_type(type);
    n->set_name(fresh(type));
    for (const auto& i : in) n->add_input(i);
    std::vector<std::string> out;
    for (int k = 0; k < outputs; ++k) {
      out.push_back(fresh(type + "_out"));
      n->add_output(out.back());
    }
    for (const auto& a : attrs) {
      auto* ap = n->add_attribute();
      ap->set_name(a.name);
      switch (a.kind) {
        case Attr::Int:
          ap->set_type(onnx::AttributeProto::INT), ap->set_i(a.i);
          break;
        case Attr::Ints:
          ap->set_type(onnx::AttributeProto::INTS);
          for (int64_t v : a.is) ap->add_ints(v);
          break;
        case Attr::Float:
          ap->set_type(onnx::AttributeProto::FLOAT), ap->set_f(a.f);
          break;
        case Attr::String:
          ap->set_type(onnx::AttributeProto::STRING), ap->set_s(a.s);
          break;
      }
    }
    return out;
  }
  std::string op(const std::string& type, const std::vector<std::string>& in, const std::vector<Attr>& attrs = {}) {
    return op_n(type, in, 1, attrs)[0];
  }

  // Layers.
  std::string linear(const std::string& x, const torch::nn::LinearImpl& l, const torch::Tensor& bias_override = {}) {
    auto y = op("MatMul", {x, init("w", l.weight.t())});
    const torch::Tensor b = bias_override.defined() ? bias_override : l.bias;
    return b.defined() ? op("Add", {y, init("b", b)}) : y;
  }
  std::string conv(const std::string& x, const torch::Tensor& w, const torch::Tensor& b, int64_t stride, int64_t pad) {
    std::vector<std::string> in = {x, init("w", w)};
    if (b.defined()) in.push_back(init("b", b));
    return op("Conv", in,
              {a_ints("kernel_shape", {w.size(2), w.size(3)}), a_ints("strides", {stride, stride}),
               a_ints("pads", {pad, pad, pad, pad})});
  }
  std::string conv(const std::string& x, const torch::nn::Conv2d& c) {
    const auto& o = c->options;
    return conv(x, c->weight, c->bias, o.stride()->at(0), c10::get<torch::ExpandingArray<2>>(o.padding())->at(0));
  }
  std::string instance_norm(const std::string& x, int64_t channels) {
    return op("InstanceNormalization",
              {x, init("ones", torch::ones({channels})), init("zeros", torch::zeros({channels}))},
              {a_float("epsilon", 1e-5f)});
  }
  std::string layer_norm(const std::string& x, const torch::nn::LayerNorm& ln) {
    return op("LayerNormalization", {x, init("ln_w", ln->weight), init("ln_b", ln->bias)},
              {a_int("axis", -1), a_float("epsilon", static_cast<float>(ln->options.eps()))});
  }
  std::string gelu(const std::string& x) {  // exact: 0.5 x (1 + erf(x / sqrt 2))
    auto e = op("Erf", {op("Div", {x, scalar(std::sqrt(2.0))})});
    return op("Mul", {op("Mul", {x, scalar(0.5)}), op("Add", {e, scalar(1.0)})});
  }
  std::string slice(const std::string& x, int64_t axis, int64_t start, int64_t end) {
    return op("Slice", {x, ints({start}), ints({end}), ints({axis})});
  }
  std::string reshape(const std::string& x, const std::vector<int64_t>& shape) {
    return op("Reshape", {x, ints(shape)});
  }
  std::string transpose(const std::string& x, const std::vector<int64_t>& perm) {
    return op("Transpose", {x}, {a_ints("perm", perm)});
  }
  std::string resize(const std::string& x, const std::vector<int64_t>& sizes) {
    return op("Resize", {x, "", "", ints(sizes)},
              {a_str("mode", "linear"), a_str("coordinate_transformation_mode", "half_pixel")});
  }

 private:
  onnx::GraphProto* g_;
  int64_t counter_ = 0;
};

std::string rotate_half(Graph& G, const std::string& x, int64_t dh) {
  auto first = G.slice(x, 3, 0, dh / 2), second = G.slice(x, 3, dh / 2, dh);
  return G.op("Concat", {G.op("Neg", {second}), first}, {Graph::a_int("axis", 3)});
}

// ---- DINO branch
std::string export_vit(Graph& G, DinoViTImpl& vit, const std::string& image, int64_t H, int64_t W) {
  const int64_t C = vit.dim(), h = H / 16, w = W / 16, P = h * w;
  const int64_t R = vit.storage_tokens.defined() ? vit.storage_tokens.size(1) : 0, prefix = 1 + R, N = prefix + P;
  auto x = G.op("Div", {G.op("Sub", {image, G.init("mean", imagenet_mean())}), G.init("std", imagenet_std())});
  x = G.conv(x, vit.patch_embed->proj);
  x = G.transpose(G.reshape(x, {1, C, P}), {0, 2, 1});
  std::vector<torch::Tensor> pre = {vit.cls_token};
  if (R > 0) pre.push_back(vit.storage_tokens);
  x = G.op("Concat", {G.init("prefix_tokens", torch::cat(pre, 1)), x}, {Graph::a_int("axis", 1)});
  auto [sin, cos] = vit.rope_embed->forward(h, w);
  const std::string s_sin = G.init("rope_sin", sin), s_cos = G.init("rope_cos", cos);
  const auto* first = vit.blocks->ptr(0)->as<ViTBlockImpl>();
  const int64_t heads = first->attn->heads, dh = C / heads;
  for (size_t b = 0; b < vit.blocks->size(); ++b) {
    auto* blk = vit.blocks->ptr(b)->as<ViTBlockImpl>();
    auto n1 = G.layer_norm(x, blk->norm1);
    auto qkv = G.linear(n1, *blk->attn->qkv, blk->attn->qkv->bias * blk->attn->bias_mask);
    qkv = G.transpose(G.reshape(qkv, {1, N, 3, heads, dh}), {2, 0, 3, 1, 4});  // [3,1,h,N,dh]
    auto parts = G.op_n("Split", {qkv, G.ints({1, 1, 1})}, 3, {Graph::a_int("axis", 0)});
    std::vector<std::string> qkvs;
    for (auto& p : parts) qkvs.push_back(G.op("Squeeze", {p, G.ints({0})}));
    auto rope = [&](const std::string& t) {
      auto pre_t = G.slice(t, 2, 0, prefix), pat = G.slice(t, 2, prefix, N);
      auto rotated = G.op("Add", {G.op("Mul", {pat, s_cos}), G.op("Mul", {rotate_half(G, pat, dh), s_sin})});
      return G.op("Concat", {pre_t, rotated}, {Graph::a_int("axis", 2)});
    };
    auto q = rope(qkvs[0]), k = rope(qkvs[1]);
    auto scores =
        G.op("Mul", {G.op("MatMul", {q, G.transpose(k, {0, 1, 3, 2})}), G.scalar(1.0 / std::sqrt(double(dh)))});
    auto attn = G.op("MatMul", {G.op("Softmax", {scores}, {Graph::a_int("axis", -1)}), qkvs[2]});
    attn = G.reshape(G.transpose(attn, {0, 2, 1, 3}), {1, N, C});
    attn = G.op("Mul", {G.linear(attn, *blk->attn->proj), G.init("ls1", blk->ls1->gamma)});
    x = G.op("Add", {x, attn});
    auto m = G.gelu(G.linear(G.layer_norm(x, blk->norm2), *blk->mlp->fc1));
    m = G.op("Mul", {G.linear(m, *blk->mlp->fc2), G.init("ls2", blk->ls2->gamma)});
    x = G.op("Add", {x, m});
  }
  x = G.slice(G.layer_norm(x, vit.norm), 1, prefix, N);
  return G.reshape(G.transpose(x, {0, 2, 1}), {1, C, h, w});
}

// ---- CNN branch
std::string export_residual(Graph& G, ResidualBlockImpl& r, const std::string& x) {
  const int64_t c = r.conv1->weight.size(0);
  auto y = G.op("Relu", {G.instance_norm(G.conv(x, r.conv1), c)});
  y = G.instance_norm(G.conv(y, r.conv2), c);
  auto skip = r.down ? G.instance_norm(G.conv(x, r.down), c) : x;
  return G.op("Relu", {G.op("Add", {skip, y})});
}

std::string export_cnn(Graph& G, CNNEncoderImpl& cnn, const std::string& image, int64_t H, int64_t W) {
  auto x = G.op("Sub", {G.op("Mul", {image, G.scalar(2.0)}), G.scalar(1.0)});
  x = G.op("Relu", {G.instance_norm(G.conv(x, cnn.stem), cnn.stem->weight.size(0))});
  const int64_t H4 = (H + 3) / 4, W4 = (W + 3) / 4;
  std::vector<std::string> scales;
  for (size_t b = 0; b < cnn.blocks->size(); ++b) {
    auto* r = cnn.blocks->ptr(b)->as<ResidualBlockImpl>();
    x = export_residual(G, *r, x);
    if (b % 2 == 1) scales.push_back(G.resize(x, {1, r->conv2->weight.size(0), H4, W4}));
  }
  auto fused = G.op(
      "Relu", {G.instance_norm(G.conv(G.op("Concat", scales, {Graph::a_int("axis", 1)}), cnn.fuse), cnn.out_channels)});
  return G.conv(fused, cnn.project);
}

// ---- frozen SqueezeNet semantic branch (encoder.semantic = squeeze): the backbone up to its tap, unit
// length over channels times sqrt(C), then the trained 1x1 projection.
std::string export_squeeze(Graph& G, const FeatureNet& net, const torch::nn::Conv2d& proj, const std::string& image) {
  auto x = G.op("Div", {G.op("Sub", {image, G.init("mean", imagenet_mean())}), G.init("std", imagenet_std())});
  const auto& layers = net.layers();
  ISPLAT_CHECK(net.taps().size() == 1, "onnx export: the semantic backbone must have one tap");
  const int64_t last = net.taps()[0], channels = net.tap_channels()[0];
  ISPLAT_CHECK(channels == proj->weight.size(1), "onnx export: the backbone's tap gives ", channels,
               " channels, the projection takes ", proj->weight.size(1));
  auto conv = [&](const std::string& in, const std::string& n, int64_t stride, int64_t pad) {
    return G.conv(in, net.param(n + ".weight"), net.param(n + ".bias"), stride, pad);
  };
  for (int64_t i = 0; i <= last; ++i) {
    const auto& l = layers[i];
    const std::string n = std::to_string(i);
    switch (l.kind) {
      case FeatureNet::Layer::Conv:
        x = conv(x, n, l.stride, l.pad);
        break;
      case FeatureNet::Layer::Relu:
        x = G.op("Relu", {x});
        break;
      case FeatureNet::Layer::MaxPool:
        x = G.op("MaxPool", {x},
                 {Graph::a_ints("kernel_shape", {l.kernel, l.kernel}), Graph::a_ints("strides", {l.stride, l.stride}),
                  Graph::a_int("ceil_mode", l.ceil ? 1 : 0)});
        break;
      case FeatureNet::Layer::Fire: {
        auto sq = G.op("Relu", {conv(x, n + ".squeeze", 1, 0)});
        x = G.op("Concat",
                 {G.op("Relu", {conv(sq, n + ".expand1x1", 1, 0)}), G.op("Relu", {conv(sq, n + ".expand3x3", 1, 1)})},
                 {Graph::a_int("axis", 1)});
        break;
      }
    }
  }
  auto norm =
      G.op("Add", {G.op("Sqrt", {G.op("ReduceSumSquare", {x}, {Graph::a_ints("axes", {1})})}), G.scalar(1e-10)});
  x = G.op("Mul", {G.op("Div", {x, norm}), G.scalar(std::sqrt(static_cast<double>(channels)))});
  return G.conv(x, proj);
}

// ---- decoder
std::string sample(Graph& G, const std::string& map, int64_t channels, const std::string& grid) {
  auto s = G.op(
      "GridSample", {map, grid},
      {Graph::a_int("align_corners", 0), Graph::a_str("mode", "bilinear"), Graph::a_str("padding_mode", "border")});
  return G.transpose(G.reshape(s, {channels, -1}), {1, 0});  // [N,C]
}

std::string export_decoder(Graph& G, ImplicitDecoderImpl& d, const std::string& dino, const std::string& cnn,
                           const std::string& grid) {
  std::string h;
  if (d.dino_dim > 0 && d.cnn_dim > 0) {
    const int64_t C = d.dino_dim;
    auto w4 = [](const torch::Tensor& w) { return w.reshape({w.size(0), w.size(1), 1, 1}); };
    auto cproj = G.conv(cnn, w4(d.cnn_proj->weight), d.cnn_proj->bias, 1, 0);
    auto wg = d.gate->weight;
    auto g_dino = G.conv(dino, w4(wg.narrow(1, 0, C)), torch::Tensor(), 1, 0);
    auto g_cnn = G.conv(cproj, w4(wg.narrow(1, C, C)), d.gate->bias, 1, 0);
    auto fd = sample(G, dino, C, grid), fc = sample(G, cproj, C, grid);
    auto g = G.op("Sigmoid", {G.op("Add", {sample(G, g_dino, C, grid), sample(G, g_cnn, C, grid)})});
    h = G.op("Add", {G.op("Mul", {g, fd}), G.op("Mul", {G.op("Sub", {G.scalar(1.0), g}), fc})});
  } else {
    h = d.dino_dim > 0 ? sample(G, dino, d.dino_dim, grid) : sample(G, cnn, d.cnn_dim, grid);
  }
  for (auto& layer : *d.mlp) h = G.op("Relu", {G.linear(h, *layer->as<torch::nn::LinearImpl>())});
  return G.linear(h, *d.head);
}

std::string export_dense(Graph& G, DenseHeadImpl& d, const std::string& dino, const std::string& cnn, int64_t H,
                         int64_t W, const std::string& grid) {
  const int64_t h4 = (H + 3) / 4, w4 = (W + 3) / 4;
  std::vector<std::string> parts;
  if (d.dino_dim > 0) parts.push_back(G.resize(dino, {1, d.dino_dim, h4, w4}));
  if (d.cnn_dim > 0) parts.push_back(G.resize(cnn, {1, d.cnn_dim, h4, w4}));
  const int64_t width = d.reduce->weight.size(0);
  auto x = G.op("Relu", {G.conv(G.op("Concat", parts, {Graph::a_int("axis", 1)}), d.reduce)});
  x = G.op("Relu", {G.conv(G.resize(x, {1, width, (H + 1) / 2, (W + 1) / 2}), d.refine1)});
  x = G.op("Relu", {G.conv(G.resize(x, {1, width, H, W}), d.refine2)});
  return sample(G, G.conv(x, d.out), kDeltaDim, grid);
}

void check_rules(InfiniSplat& model) {
  static const std::set<std::string> supported = {
      "isplat::InfiniSplatImpl",  "isplat::DualEncoderImpl", "isplat::DinoViTImpl",       "isplat::PatchEmbedImpl",
      "isplat::RopeEmbedImpl",    "isplat::ViTBlockImpl",    "isplat::AttentionImpl",     "isplat::LayerScaleImpl",
      "isplat::MlpImpl",          "isplat::CNNEncoderImpl",  "isplat::ResidualBlockImpl", "isplat::ImplicitDecoderImpl",
      "isplat::DenseHeadImpl",    "torch::nn::LinearImpl",   "torch::nn::Conv2dImpl",     "torch::nn::LayerNormImpl",
      "torch::nn::ModuleListImpl"};
  for (const auto& m : model->named_modules("model", true))
    if (!supported.count(m.value()->name()))
      fail("ONNX export: no export rule for layer '", m.value()->name(), "' (at ", m.key(), ")");
}

}  // namespace

onnx::ModelProto export_onnx(InfiniSplat& model, const OnnxExportOptions& o) {
  ISPLAT_CHECK(o.opset >= 17, "ONNX export: opset ", o.opset, " is too old (LayerNormalization needs 17)");
  ISPLAT_CHECK(o.width >= 16 && o.height >= 16 && o.width % 16 == 0 && o.height % 16 == 0, "ONNX export: image size ",
               o.width, "x", o.height, " must be multiples of 16");
  ISPLAT_CHECK(model->options.decoder.mode != "none", "ONNX export: decoder.mode = none has no learned part to export");
  check_rules(model);
  torch::NoGradGuard no_grad;
  model->eval();
  onnx::ModelProto mp;
  mp.set_ir_version(8);
  mp.set_producer_name("InfiniSplat-C++");
  mp.set_producer_version(ISPLAT_VERSION);
  auto* opset = mp.add_opset_import();
  opset->set_domain("");
  opset->set_version(o.opset);
  auto* g = mp.mutable_graph();
  g->set_name("infinisplat_encoder_decoder");
  auto add_io = [](google::protobuf::RepeatedPtrField<onnx::ValueInfoProto>* list, const std::string& name,
                   const std::vector<std::variant<int64_t, std::string>>& dims) {
    auto* v = list->Add();
    v->set_name(name);
    auto* t = v->mutable_type()->mutable_tensor_type();
    t->set_elem_type(onnx::TensorProto::FLOAT);
    for (const auto& d : dims) {
      auto* dim = t->mutable_shape()->add_dim();
      if (std::holds_alternative<int64_t>(d))
        dim->set_dim_value(std::get<int64_t>(d));
      else
        dim->set_dim_param(std::get<std::string>(d));
    }
  };
  add_io(g->mutable_input(), "image", {int64_t{1}, int64_t{3}, o.height, o.width});
  add_io(g->mutable_input(), "uv", {std::string("num_supports"), int64_t{2}});
  Graph G(g);
  std::string dino, cnn;
  if (model->encoder->squeeze)
    dino = export_squeeze(G, *model->encoder->squeeze, model->encoder->squeeze_proj, "image");
  if (model->encoder->vit) dino = export_vit(G, *model->encoder->vit, "image", o.height, o.width);
  if (model->encoder->cnn) cnn = export_cnn(G, *model->encoder->cnn, "image", o.height, o.width);
  // grid = clamp(uv * (2/W, 2/H) - 1, +-(1 - 1e-6)) as [1,1,N,2]
  const double lim = 1.0 - 1e-6;
  auto grid = G.op("Sub", {G.op("Mul", {"uv", G.init("uv_scale", torch::tensor({2.0f / o.width, 2.0f / o.height}))}),
                           G.scalar(1.0)});
  grid = G.reshape(G.op("Clip", {grid, G.init("lo", torch::tensor(-lim, torch::kFloat32)),
                                 G.init("hi", torch::tensor(lim, torch::kFloat32))}),
                   {1, 1, -1, 2});
  std::string delta;
  if (model->decoder)
    delta = export_decoder(G, *model->decoder, dino, cnn, grid);
  else
    delta = export_dense(G, *model->dense, dino, cnn, o.height, o.width, grid);
  G.op("Identity", {delta});
  g->mutable_node(g->node_size() - 1)->set_output(0, "delta");  // the graph output under its public name
  add_io(g->mutable_output(), "delta", {std::string("num_supports"), int64_t{kDeltaDim}});
  return mp;
}

int64_t save_onnx(const onnx::ModelProto& model, const std::string& path) {
  try {
    onnx::checker::check_model(model);
  } catch (const std::exception& e) {
    fail(path, ": the exported graph fails onnx::checker::check_model: ", e.what());
  }
  std::string bytes;
  if (!model.SerializeToString(&bytes)) fail(path, ": cannot serialize the ONNX model");
  write_file_atomic(path, bytes);
  return static_cast<int64_t>(bytes.size());
}

}  // namespace isplat
