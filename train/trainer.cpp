// Trainer: steps, schedule, validation, logs and checkpoints for both training tasks.
#include "train/trainer.h"

#include <ATen/core/Generator.h>
#include <torch/torch.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <atomic>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>

#include "core/config.h"
#include "core/error.h"
#include "core/log.h"
#include "core/parse.h"
#include "core/progress.h"
#include "geometry/camera_torch.h"
#include "io/atomic_file.h"
#include "io/checkpoint.h"
#include "io/image_io.h"
#include "io/safetensors.h"
#include "io/tensor_image.h"
#include "loss/knn.h"
#include "metrics/mask.h"
#include "metrics/metrics.h"
#include "render/render.h"

namespace isplat {
namespace fs = std::filesystem;

namespace {
std::atomic<bool> g_stop{false};

using Clock = std::chrono::steady_clock;

std::vector<Sequence> read_split(const HypersimOptions& base, const std::string& split) {
  HypersimOptions h = base;
  h.split = split;
  return read_hypersim(h).sequences;
}

bool finite(const torch::Tensor& t) {
  return torch::isfinite(t).all().item<bool>();
}
}  // namespace

void Trainer::request_stop() {
  g_stop = true;
}

Trainer::Trainer(const TrainConfig& config) : config_(config), run_dir_(config.train.out) {
  torch::manual_seed(static_cast<uint64_t>(config.runtime.seed));
  fs::create_directories(fs::path(run_dir_) / "checkpoints");
  fs::create_directories(fs::path(run_dir_) / "val");
  log_path_ = (fs::path(run_dir_) / "train_log.jsonl").string();
  write_file_atomic((fs::path(run_dir_) / "config.json").string(), config_to_json(config_).dump(2) + "\n");

  auto train_seqs = read_split(config.data.hypersim, config.data.hypersim.split);
  ISPLAT_CHECK(!train_seqs.empty(), "train: no usable trajectories in ", config.data.hypersim.root, " split '",
               config.data.hypersim.split, "' (config key data.hypersim)");
  train_sampler_ = std::make_unique<TupleSampler>(std::move(train_seqs), config.data.tuples,
                                                  static_cast<uint64_t>(config.runtime.seed));
  try {
    auto val_seqs = read_split(config.data.hypersim, config.data.val_split);
    if (!val_seqs.empty())
      val_sampler_ = std::make_unique<TupleSampler>(std::move(val_seqs), config.data.tuples,
                                                    static_cast<uint64_t>(config.runtime.seed) + 1);
  } catch (const Error& e) {
    log_warn("train: no validation set (", e.what(), "); validation is skipped");
  }
  if (!val_sampler_) log_warn("train: split '", config.data.val_split, "' is empty; validation is skipped");

  std::vector<torch::Tensor> params;
  if (config.task == "gaussians") {
    pipeline_ = std::make_unique<Pipeline>(config.model);
    if (config.loss.perceptual > 0) perceptual_ = std::make_unique<PerceptualLoss>(config.loss);
    log_info("train: prior ", pipeline_->prior().describe(), "; perceptual loss ",
             perceptual_ ? perceptual_->describe() : std::string("off (weight 0)"));
    params = pipeline_->model()->parameters();
  } else {
    depth_net_ = LearnedDepthNet(config.model.prior.learned_width);
    params = depth_net_->parameters();
  }
  int64_t count = 0;
  for (const auto& p : params) count += p.numel();
  log_info("train: task ", config.task, ", ", count, " trainable parameters, ", config.train.steps, " steps, batch ",
           config.data.batch_size, " x (1 context + ", config.data.tuples.targets, " targets) at ",
           config.data.tuples.width, "x", config.data.tuples.height);
  optimizer_ = std::make_unique<torch::optim::AdamW>(params, torch::optim::AdamWOptions(config.optim.lr)
                                                                 .betas({config.optim.beta1, config.optim.beta2})
                                                                 .weight_decay(config.optim.weight_decay));
}

Trainer::~Trainer() = default;

torch::nn::Module& Trainer::trainable() {
  if (pipeline_) return *pipeline_->model();
  return *depth_net_;
}

const torch::nn::Module& Trainer::trainable() const {
  return const_cast<Trainer*>(this)->trainable();
}

std::map<std::string, torch::Tensor> Trainer::gaussian_losses(const Batch& batch, StepStats& stats, bool train,
                                                              std::vector<torch::Tensor>* predictions) {
  const int64_t B = batch.size(), T = batch.targets(), H = batch.target_image.size(3), W = batch.target_image.size(4);
  const LossOptions& lo = config_.loss;
  auto zero = torch::zeros({});
  std::map<std::string, torch::Tensor> acc = {{"l1", zero}, {"perceptual", zero}, {"scale", zero}, {"smooth", zero}};
  for (int64_t b = 0; b < B; ++b) {
    PriorInput in;
    in.image = batch.context_image[b];
    in.K = batch.context_K[b];
    in.depth = batch.context_depth[b];
    in.valid = batch.context_valid[b];
    in.seed = mix_seed(static_cast<uint64_t>(config_.runtime.seed), static_cast<uint64_t>(step_ * B + b));
    Prediction p = pipeline_->run(in, batch.context_T[b], train);
    for (const auto& [k, v] : p.timings_ms) stats.timings_ms[k] += v;
    stats.supports += p.supports.count();
    // Diverged weights give non-finite Gaussians, which the renderer rejects: report the step as
    // non-finite so the loop skips it (and stops after train.max_bad_steps).
    const auto& gs = p.gaussians;
    if (!finite(gs.means) || !finite(gs.scales) || !finite(gs.quats) || !finite(gs.colors) || !finite(gs.opacities)) {
      acc["total"] = torch::full({}, std::numeric_limits<float>::quiet_NaN());
      return acc;
    }

    auto t0 = Clock::now();
    const Camera cams{batch.target_K[b], batch.target_T[b], W, H};
    RenderOutput out = render(p.gaussians, cams, config_.render);
    stats.timings_ms["render_fwd"] += ms_since(t0);
    if (train) {  // time the renderer's share of the backward pass with gradient hooks
      auto* st = &stats;
      auto start = std::make_shared<Clock::time_point>();
      out.rgb.register_hook([start](torch::Tensor g) {
        *start = Clock::now();
        return g;
      });
      p.gaussians.means.register_hook([start, st](torch::Tensor g) {
        st->timings_ms["render_bwd"] += ms_since(*start);
        return g;
      });
    }
    t0 = Clock::now();
    auto rgb = torch::clamp(out.rgb, 0.0, 1.0);
    auto pred = config_.model.composer.linear_rgb ? linear_to_srgb(rgb) : rgb;
    auto target = batch.target_image[b];
    torch::Tensor mask;
    if (config_.train.target_mask == "projected") {
      const View src = to_view(Camera{batch.context_K[b], batch.context_T[b], W, H});
      std::vector<torch::Tensor> masks;
      for (int64_t t = 0; t < T; ++t)
        masks.push_back(projected_mask(batch.context_depth[b], batch.context_valid[b], src,
                                       to_view(Camera{batch.target_K[b][t], batch.target_T[b][t], W, H})));
      mask = torch::stack(masks).unsqueeze(1);
    } else {
      mask = torch::ones({T, 1, H, W});
    }
    // Pixels outside the mask take the target's value, so no term sees them.
    auto composite = pred * mask + target * (1 - mask);
    if (predictions) predictions->push_back(composite.detach());
    acc["l1"] = acc["l1"] + ((pred - target).abs() * mask).sum() / (3.0 * mask.sum() + 1e-6);
    if (perceptual_ && perceptual_->enabled())
      acc["perceptual"] = acc["perceptual"] + (*perceptual_)(composite, target);
    auto z = transform_points(batch.context_T[b].to(p.gaussians.means.scalar_type()), p.gaussians.means).select(1, 2);
    acc["scale"] = acc["scale"] + scale_range_loss(p.gaussians.scales, z, lo.scale_bounds.at(0), lo.scale_bounds.at(1));
    if (lo.smooth > 0) {
      const auto nb = knn_2d(p.supports.uv, lo.knn);
      acc["smooth"] = acc["smooth"] + smoothness_loss(p.gaussians.scales, p.gaussians.opacities, nb);
    }
    stats.timings_ms["losses"] += ms_since(t0);
  }
  for (auto& [k, v] : acc) v = v / static_cast<double>(B);
  acc["total"] = lo.rgb * acc["l1"] + lo.perceptual * acc["perceptual"] +
                 lo.reg * (lo.scale * acc["scale"] + lo.smooth * acc["smooth"]);
  return acc;
}

std::map<std::string, torch::Tensor> Trainer::depth_losses(const Batch& batch) {
  auto pred = depth_net_->forward_log(batch.context_image).squeeze(1);  // [B,H,W]
  auto valid = batch.context_valid > 0.5;
  const int64_t n = valid.sum().item<int64_t>();
  ISPLAT_CHECK(n > 0, "depth training: a batch without valid depth");
  auto d = pred.masked_select(valid) - torch::log(batch.context_depth.masked_select(valid));
  auto l1 = d.abs().mean();
  auto silog = torch::sqrt(torch::clamp_min((d * d).mean() - 0.85 * d.mean().pow(2), 1e-12));
  return {{"l1_log", l1}, {"silog", silog}, {"total", l1 + silog}};
}

StepStats Trainer::train_step() {
  StepStats s;
  auto t0 = Clock::now();
  if (!loader_)
    loader_ = std::make_unique<BatchLoader>(*train_sampler_, config_.data.batch_size, config_.data.workers,
                                            config_.data.prefetch, step_);
  const Batch batch = loader_->next();
  s.timings_ms["data"] = ms_since(t0);
  s.lr = scheduled_lr(config_.optim, step_, config_.train.steps);
  for (auto& g : optimizer_->param_groups()) static_cast<torch::optim::AdamWOptions&>(g.options()).lr(s.lr);
  trainable().train();
  optimizer_->zero_grad();
  auto losses = config_.task == "gaussians" ? gaussian_losses(batch, s, true) : depth_losses(batch);
  for (const auto& [k, v] : losses) s.losses[k] = v.item<double>();
  auto& total = losses.at("total");
  bool ok = finite(total);
  if (ok) {
    t0 = Clock::now();
    total.backward();
    s.timings_ms["backward"] = ms_since(t0);
    for (const auto& p : trainable().parameters())
      if (p.grad().defined() && !finite(p.grad())) {
        ok = false;
        break;
      }
  }
  if (!ok) {
    s.skipped = true;
    ++bad_steps_;
    log_warn("train: step ", step_, " has a non-finite loss or gradient (", s.losses["total"], "); skipped (",
             bad_steps_, " in a row)");
    if (bad_steps_ >= config_.train.max_bad_steps)
      fail("train: ", bad_steps_,
           " consecutive non-finite steps (train.max_bad_steps); stopping. Lower optim.lr, "
           "check the data for broken depth, or raise train.max_bad_steps.");
  } else {
    bad_steps_ = 0;
    t0 = Clock::now();
    if (config_.optim.grad_clip > 0)
      torch::nn::utils::clip_grad_norm_(trainable().parameters(), config_.optim.grad_clip);
    optimizer_->step();
    s.timings_ms["optim"] = ms_since(t0);
  }
  ++step_;
  return s;
}

double Trainer::validate(bool write_images) {
  if (!val_sampler_) return std::numeric_limits<double>::quiet_NaN();
  torch::NoGradGuard g;
  trainable().eval();
  double total = 0, psnr_sum = 0;
  int64_t psnr_n = 0;
  for (int64_t i = 0; i < config_.data.val_tuples; ++i) {
    const Batch batch = collate({val_sampler_->sample(i)});
    StepStats s;
    std::vector<torch::Tensor> preds;
    auto losses = config_.task == "gaussians" ? gaussian_losses(batch, s, false, &preds) : depth_losses(batch);
    total += losses.at("total").item<double>();
    if (!preds.empty()) {
      for (int64_t t = 0; t < batch.targets(); ++t) {
        const double p = psnr(preds[0][t], batch.target_image[0][t]);
        if (std::isfinite(p)) psnr_sum += p, ++psnr_n;
      }
      if (write_images && i < config_.train.val_images) write_val_images(batch, preds, i);
    }
  }
  const double mean = total / config_.data.val_tuples;
  std::ofstream log(log_path_, std::ios::app);
  nlohmann::json j = {{"step", step_}, {"val_loss", mean}};
  if (psnr_n) j["val_psnr_masked"] = psnr_sum / psnr_n;
  log << j.dump() << "\n";
  log_info("validation at step ", step_, ": loss ", mean,
           psnr_n ? cat(", masked PSNR ", psnr_sum / psnr_n, " dB") : "");
  return mean;
}

void Trainer::write_val_images(const Batch& batch, const std::vector<torch::Tensor>& preds, int64_t index) {
  // One row per target: context | target | prediction | |error| x 4.
  std::vector<cv::Mat> rows;
  for (int64_t t = 0; t < batch.targets(); ++t) {
    const auto target = batch.target_image[0][t], pred = preds[0][t];
    const auto err = ((pred - target).abs() * 4.0).clamp(0, 1);
    std::vector<cv::Mat> cols = {tensor_to_image(batch.context_image[0]), tensor_to_image(target),
                                 tensor_to_image(pred), tensor_to_image(err)};  // write_image clamps to [0, 1]
    cv::Mat row;
    cv::hconcat(cols, row);
    rows.push_back(row);
  }
  cv::Mat panel;
  cv::vconcat(rows, panel);
  char name[64];
  std::snprintf(name, sizeof name, "step_%06lld_tuple%lld.png", static_cast<long long>(step_),
                static_cast<long long>(index));
  write_image((fs::path(run_dir_) / "val" / name).string(), panel);
}

void Trainer::save(const std::string& path, bool with_optimizer) const {
  Checkpoint ck;
  put_module(ck, trainable());
  if (with_optimizer) {
    torch::serialize::OutputArchive archive;
    optimizer_->save(archive);
    std::ostringstream bytes;
    archive.save_to(bytes);
    ck.tensors["optim/state"] = bytes_to_tensor(bytes.str());
  }
  ck.tensors["rng/torch"] = at::detail::getDefaultCPUGenerator().get_state();
  ck.metadata["step"] = std::to_string(step_);
  ck.metadata["task"] = config_.task;
  ck.metadata["best_val"] = cat(best_val_);
  ck.metadata["config"] = config_to_json(config_).dump();
  // Carry the learned depth prior's weights, so the checkpoint alone predicts from a photo.
  if (pipeline_)
    if (const torch::nn::Module* prior_net = pipeline_->prior().embeddable_weights())
      put_module(ck, *prior_net, "prior/");
  save_checkpoint(path, ck);
}

void Trainer::resume(const std::string& requested) {
  std::string path = requested;
  if (path == "auto") {
    path = (fs::path(run_dir_) / "checkpoints" / "last.safetensors").string();
    if (!fs::exists(path)) {
      log_info("train: --resume auto: no checkpoint in ", run_dir_, "; starting from scratch");
      return;
    }
  }
  const Checkpoint ck = load_checkpoint(path);
  auto it = ck.metadata.find("task");
  if (it != ck.metadata.end() && it->second != config_.task)
    fail(path, ": checkpoint is for task '", it->second, "', the config says '", config_.task, "'");
  load_module(ck, trainable(), path);
  if (!ck.tensors.count("optim/state"))
    fail(path, ": holds no optimizer state (a weights-only checkpoint such as init); it cannot be resumed");
  torch::serialize::InputArchive archive;
  std::istringstream bytes(tensor_to_bytes(ck.tensors.at("optim/state")));
  archive.load_from(bytes);
  optimizer_->load(archive);
  at::Generator gen = at::detail::getDefaultCPUGenerator();
  gen.set_state(ck.tensors.at("rng/torch"));
  step_ = ck.step();
  auto bv = ck.metadata.find("best_val");
  if (bv != ck.metadata.end()) best_val_ = parse_double(bv->second).value_or(std::numeric_limits<double>::infinity());
  loader_.reset();  // restart the data stream at the resumed step
  log_info("train: resumed from ", path, " at step ", step_);
}

namespace {
// Points `alias` at the same bytes as `file` (hard link, renamed into place atomically), or copies.
void alias_file(const fs::path& file, const fs::path& alias) {
  const fs::path tmp = alias.parent_path() / ("." + alias.filename().string() + ".tmp");
  std::error_code ec;
  fs::remove(tmp, ec);
  fs::create_hard_link(file, tmp, ec);
  if (ec) fs::copy_file(file, tmp, fs::copy_options::overwrite_existing);
  fs::rename(tmp, alias);
}
}  // namespace

void Trainer::checkpoint(bool periodic) {
  const fs::path dir = fs::path(run_dir_) / "checkpoints";
  if (!periodic) {
    save((dir / "last.safetensors").string());
    return;
  }
  char name[64];
  std::snprintf(name, sizeof name, "step_%06lld.safetensors", static_cast<long long>(step_));
  save((dir / name).string());
  alias_file(dir / name, dir / "last.safetensors");  // one file on disk for both names
  std::vector<fs::path> periodic_files;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().filename().string().rfind("step_", 0) == 0) periodic_files.push_back(e.path());
  std::sort(periodic_files.begin(), periodic_files.end());
  while (static_cast<int64_t>(periodic_files.size()) > config_.train.keep_last) {
    fs::remove(periodic_files.front());  // last/best keep their own links
    periodic_files.erase(periodic_files.begin());
  }
}

void Trainer::write_log(const StepStats& s) {
  nlohmann::json j = {{"step", step_},          {"lr", s.lr},          {"loss", s.losses}, {"time_ms", s.timings_ms},
                      {"supports", s.supports}, {"skipped", s.skipped}};
  std::ofstream log(log_path_, std::ios::app);
  log << j.dump() << "\n";
}

int Trainer::run() {
  const fs::path ckdir = fs::path(run_dir_) / "checkpoints";
  if (step_ == 0) save((ckdir / "init.safetensors").string(), false);  // the untrained model, for comparisons
  std::signal(SIGINT, [](int) { request_stop(); });
  std::signal(SIGTERM, [](int) { request_stop(); });
  ProgressBar bar("train", config_.train.steps - step_, "step");
  std::map<std::string, double> time_sum;
  int64_t timed = 0;
  while (step_ < config_.train.steps) {
    const StepStats s = train_step();
    if (step_ % config_.train.log_every == 0 || step_ == config_.train.steps) write_log(s);
    for (const auto& [k, v] : s.timings_ms) time_sum[k] += v;
    ++timed;
    std::string post = cat("loss ", std::setprecision(4), s.losses.at("total"));
    for (const char* k : {"l1", "perceptual", "silog"})
      if (s.losses.count(k)) post += cat(" ", k, " ", std::setprecision(3), s.losses.at(k));
    bar.postfix(post);
    bar.tick();
    const bool periodic = step_ % config_.train.checkpoint_every == 0 || step_ == config_.train.steps;
    bool improved = false;
    if (step_ % config_.train.val_every == 0 || step_ == config_.train.steps) {
      const double v = validate(true);
      improved = std::isfinite(v) && v < best_val_;
      if (improved) best_val_ = v;  // before saving, so the checkpoint records it
    }
    if (periodic) checkpoint(true);
    if (improved) {
      if (periodic)
        alias_file(ckdir / "last.safetensors", ckdir / "best.safetensors");
      else
        save((ckdir / "best.safetensors").string());
    }
    if (g_stop) {
      bar.finish();
      checkpoint(false);
      log_warn("train: interrupted; checkpoint written to ", (ckdir / "last.safetensors").string(),
               " (resume with --resume auto)");
      return 130;
    }
  }
  bar.finish();
  if (config_.task == "depth") {  // the frozen prior's weights, under the net's own names
    std::map<std::string, torch::Tensor> w;
    for (const auto& p : depth_net_->named_parameters(true)) w[p.key()] = p.value().detach();
    write_safetensors((fs::path(run_dir_) / "depth_net.safetensors").string(), w);
  }
  nlohmann::json summary = {{"steps", step_}, {"best_val_loss", best_val_}};
  for (auto& [k, v] : time_sum) summary["mean_step_time_ms"][k] = v / std::max<int64_t>(1, timed);
  write_file_atomic((fs::path(run_dir_) / "summary.json").string(), summary.dump(2) + "\n");
  std::string breakdown;
  for (auto& [k, v] : time_sum)
    breakdown += cat(" ", k, " ", std::fixed, std::setprecision(0), v / std::max<int64_t>(1, timed));
  log_info("train: done, ", step_, " steps; mean ms per step:", breakdown, "; run folder ", run_dir_);
  return 0;
}

}  // namespace isplat
