// Trainer: steps, schedule, validation, logs and checkpoints for both training tasks.
#include "train/trainer.h"

#include <ATen/core/Generator.h>
#include <torch/torch.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <ctime>
#include <filesystem>

#include "core/build_info.h"
#include "core/config.h"
#include "core/error.h"
#include "core/log.h"
#include "core/parse.h"
#include "core/progress.h"
#include "io/atomic_file.h"
#include "io/chart.h"
#include "io/checkpoint.h"
#include "io/folder_lock.h"
#include "io/panel.h"
#include "io/safetensors.h"
#include "metrics/metrics.h"
#include "model/model_io.h"
#include "train/fused_adamw.h"

namespace isplat {
namespace fs = std::filesystem;

std::vector<Sequence> read_training_sequences(const DataOptions& data, const std::string& split) {
  HypersimOptions h = data.hypersim;
  h.split = split;
  std::vector<Sequence> out = read_hypersim(h).sequences;
  for (const std::string& root : data.extra_roots) {
    ISPLAT_CHECK(fs::is_directory(root), root, ": no such folder (config key data.extra_roots)");
    h.root = root;
    auto more = read_hypersim(h).sequences;
    out.insert(out.end(), std::make_move_iterator(more.begin()), std::make_move_iterator(more.end()));
  }
  return out;
}

namespace {
std::atomic<bool> g_stop{false};

using Clock = std::chrono::steady_clock;

double process_cpu_seconds() {
  timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec + ts.tv_nsec * 1e-9;
}

}  // namespace

void Trainer::request_stop() {
  g_stop = true;
}

Trainer::Trainer(const TrainConfig& config)
    : config_(config),
      precision_(resolve_precision(config.runtime.precision)),
      run_dir_(config.train.out),
      checkpoints_((fs::path(config.train.out) / "checkpoints").string(), config.train.keep_last) {
  torch::manual_seed(static_cast<uint64_t>(config.runtime.seed));
  cpu_start_ = process_cpu_seconds();
  if (config.dist.world_size > 1) dp_ = std::make_unique<DataParallel>(config.dist);
  if (writer()) {  // only rank 0 writes (and locks) the run folder
    lock_ = std::make_unique<FolderLock>(run_dir_);
    const std::string val_dir = (fs::path(run_dir_) / "val").string();
    std::error_code ec;
    fs::create_directories(val_dir, ec);
    if (ec) fail(val_dir, ": cannot create the folder: ", ec.message());
    // Under the lock nobody else writes here: any temporary is what a killed write left behind.
    const int64_t stale = remove_stale_temporaries(run_dir_) + remove_stale_temporaries(val_dir) +
                          checkpoints_.remove_stale_temporaries();
    if (stale > 0) log_info("train: removed ", stale, " temporary file(s) of interrupted writes in ", run_dir_);
    log_ = std::make_unique<JsonlWriter>((fs::path(run_dir_) / "train_log.jsonl").string());
    write_file_atomic((fs::path(run_dir_) / "config.json").string(), config_to_json(config_).dump(2) + "\n");
  }

  auto train_seqs = read_training_sequences(config.data, config.data.hypersim.split);
  ISPLAT_CHECK(!train_seqs.empty(), "train: no usable trajectories in ", config.data.hypersim.root, " split '",
               config.data.hypersim.split, "' (config key data.hypersim)");
  train_sampler_ = std::make_unique<TupleSampler>(std::move(train_seqs), config.data.tuples,
                                                  static_cast<uint64_t>(config.runtime.seed));
  try {
    auto val_seqs = read_training_sequences(config.data, config.data.val_split);
    TupleOptions val_tuples = config.data.tuples;
    val_tuples.augment = AugmentOptions{};  // validation scores the data as it is
    if (!val_seqs.empty())
      val_sampler_ = std::make_unique<TupleSampler>(std::move(val_seqs), val_tuples,
                                                    static_cast<uint64_t>(config.runtime.seed) + 1);
  } catch (const Error& e) {
    log_warn("train: no validation set (", e.what(), "); validation is skipped");
  }
  if (!val_sampler_) log_warn("train: split '", config.data.val_split, "' is empty; validation is skipped");

  task_ = make_train_task(config);
  log_info("train: ", task_->describe());
  const auto params = task_->module().parameters();
  int64_t count = 0;
  for (const auto& p : params) count += p.numel();
  log_info("train: task ", config.task, ", ", count, " trainable parameters, ", config.train.steps, " steps, batch ",
           config.data.batch_size, " x (1 context + ", config.data.tuples.targets, " targets) at ",
           config.data.tuples.width, "x", config.data.tuples.height);
  const auto adamw = [&](double lr) {
    return torch::optim::AdamWOptions(lr)
        .betas({config.optim.beta1, config.optim.beta2})
        .weight_decay(config.optim.weight_decay);
  };
  std::vector<torch::optim::OptimizerParamGroup> groups;
  int64_t grouped = 0;
  for (auto& g : task_->param_groups()) {
    for (const auto& p : g.params) grouped += p.numel();
    lr_scales_.push_back(g.lr_scale);
    if (g.lr_scale != 1.0)
      log_info("train: ", g.params.size(), " parameter tensors at ", g.lr_scale, " x the learning rate");
    groups.emplace_back(std::move(g.params),
                        std::make_unique<torch::optim::AdamWOptions>(adamw(config.optim.lr * g.lr_scale)));
  }
  ISPLAT_CHECK(grouped == count, "train: the optimizer's parameter groups hold ", grouped, " weights, the task has ",
               count);
  optimizer_ = std::make_unique<FusedAdamW>(std::move(groups), adamw(config.optim.lr));
  if (dp_) {  // every rank starts from rank 0's weights (and buffers)
    std::vector<torch::Tensor> state = params;
    for (const auto& b : task_->module().buffers()) state.push_back(b);
    dp_->broadcast(state);
    log_info("train: rank ", dp_->rank(), " of ", dp_->world_size(), "; global batch ",
             config.data.batch_size * dp_->world_size(), "; rank 0 writes ", run_dir_);
  }
}

bool Trainer::writer() const {
  return !dp_ || dp_->rank() == 0;
}

Trainer::~Trainer() = default;

torch::nn::Module& Trainer::trainable() {
  return task_->module();
}

const torch::nn::Module& Trainer::trainable() const {
  return const_cast<Trainer*>(this)->trainable();
}

double Trainer::cpu_seconds() const {
  return cpu_offset_ + process_cpu_seconds() - cpu_start_;
}

void Trainer::synchronize_gradients(StepStats& s) {
  // One process: the gradients are already the batch mean. Data-parallel: the mean over ranks.
  if (!dp_) return;
  dp_->average_gradients(trainable().parameters());
  s.timings_ms["allreduce"] = dp_->last_allreduce_ms();
}

StepStats Trainer::train_step() {
  const PrecisionScope precision(precision_);
  StepStats s;
  const auto t_step = Clock::now();
  auto t0 = Clock::now();
  const int64_t rank = dp_ ? dp_->rank() : 0, world = dp_ ? dp_->world_size() : 1;
  if (!loader_)
    loader_ = std::make_unique<BatchLoader>(*train_sampler_, config_.data.batch_size, config_.data.workers,
                                            config_.data.prefetch, step_, rank, world);
  const Batch batch = loader_->next();
  s.timings_ms["data"] = ms_since(t0);
  s.lr = scheduled_lr(config_.optim, step_, config_.train.steps);
  auto& groups = optimizer_->param_groups();
  for (size_t i = 0; i < groups.size(); ++i)
    static_cast<torch::optim::AdamWOptions&>(groups[i].options()).lr(s.lr * lr_scales_[i]);
  trainable().train();
  optimizer_->zero_grad();
  // Global sample index of this rank's first tuple: rank r of W takes tuples r*B .. r*B+B-1 of each global batch.
  const int64_t first_sample = (step_ * world + rank) * config_.data.batch_size;
  auto losses = task_->losses(batch, first_sample, /*train=*/true, s, nullptr);
  for (const auto& [k, v] : losses) s.losses[k] = v.item<double>();
  auto& total = losses.at("total");
  bool ok = all_finite(total);
  stop_ = g_stop;
  if (dp_) {  // one decision for all ranks: skip when any rank's loss is non-finite, stop when any rank was asked to
    const auto agreed = dp_->sum({ok ? 1.0 : 0.0, stop_ ? 1.0 : 0.0, ok ? s.losses["total"] : 0.0});
    ok = agreed[0] == static_cast<double>(world);
    stop_ = agreed[1] > 0;
    if (ok) s.losses["total_all_ranks"] = agreed[2] / world;
  }
  if (ok) {
    t0 = Clock::now();
    total.backward();
    s.timings_ms["backward"] = ms_since(t0);
    synchronize_gradients(s);
    for (const auto& p : trainable().parameters())
      if (p.grad().defined() && !all_finite(p.grad())) {
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
  s.step_ms = ms_since(t_step);
  return s;
}

double Trainer::validate(bool write_images) {
  if (!val_sampler_) return std::numeric_limits<double>::quiet_NaN();
  const PrecisionScope precision(precision_);
  torch::NoGradGuard g;
  trainable().eval();
  double total = 0, psnr_sum = 0;
  int64_t psnr_n = 0;
  for (int64_t i = 0; i < config_.data.val_tuples; ++i) {
    const Batch batch = collate({val_sampler_->sample(i)});
    StepStats s;
    std::vector<RenderedViews> views;
    const auto losses = task_->losses(batch, i, /*train=*/false, s, &views);
    total += losses.at("total").item<double>();
    if (views.empty()) continue;
    for (int64_t t = 0; t < batch.targets(); ++t) {  // masked PSNR: only the pixels the loss scores
      const double p = psnr(views[0].render[t], batch.target_image[0][t], views[0].mask[t]);
      if (std::isfinite(p)) psnr_sum += p, ++psnr_n;
    }
    if (write_images && i < config_.train.val_images) write_val_images(batch, views[0], i);
  }
  const double mean = total / config_.data.val_tuples;
  nlohmann::json j = {{"step", step_}, {"val_loss", mean}, {"cpu_s", cpu_seconds()}};
  if (psnr_n) j["val_psnr_masked"] = psnr_sum / psnr_n;
  log_->write(j);
  write_curves();
  log_info("validation at step ", step_, ": loss ", mean,
           psnr_n ? cat(", masked PSNR ", psnr_sum / psnr_n, " dB") : "");
  return mean;
}

void Trainer::write_val_images(const Batch& batch, const RenderedViews& views, int64_t index) {
  // One row per target: context | target | raw render (outside the mask dimmed, its border outlined) | |error| x 4.
  std::vector<std::vector<torch::Tensor>> rows;
  for (int64_t t = 0; t < batch.targets(); ++t) {
    const auto target = batch.target_image[0][t], pred = views.render[t], mask = views.mask[t];
    rows.push_back({batch.context_image[0], target, outline_mask(pred, mask),
                    outline_mask(((pred - target).abs() * 4.0).clamp(0, 1), mask)});
  }
  char name[64];
  std::snprintf(name, sizeof name, "step_%06lld_tuple%lld.png", static_cast<long long>(step_),
                static_cast<long long>(index));
  write_panel((fs::path(run_dir_) / "val" / name).string(), rows);
}

Checkpoint Trainer::make_checkpoint(bool with_optimizer) const {
  Checkpoint ck;
  put_module(ck, const_cast<Trainer*>(this)->trainable());
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
  ck.metadata["cpu_s"] = cat(std::setprecision(17), cpu_seconds());
  ck.metadata["config"] = config_to_json(config_).dump();
  ck.metadata["config_version"] = std::to_string(kModelConfigVersion);  // the defaults it was trained under
  task_->add_to_checkpoint(ck);
  return ck;
}

void Trainer::save(const std::string& path, bool with_optimizer) const {
  save_checkpoint(path, make_checkpoint(with_optimizer));
}

void Trainer::resume(const std::string& requested) {
  std::string path = requested;
  Checkpoint ck;
  if (path == "auto") {
    auto found = checkpoints_.newest_intact();
    if (!found) {
      log_info("train: --resume auto: no intact checkpoint in ", run_dir_, "; starting from scratch");
      return;
    }
    path = found->path;
    ck = std::move(found->checkpoint);
  } else {
    ck = load_checkpoint(path);
  }
  auto it = ck.metadata.find("task");
  if (it != ck.metadata.end() && it->second != config_.task)
    fail(path, ": checkpoint is for task '", it->second, "', the config says '", config_.task, "'");
  // A run resumes the model it started: a changed model key, or a default that changed since the run began
  // (config_version), would otherwise go on training another model in silence.
  const auto started = config_to_json(model_options_from_checkpoint(ck, path)), now = config_to_json(config_.model);
  if (started != now) {
    std::string keys;
    const auto patch = nlohmann::ordered_json::diff(started, now);
    for (size_t i = 0; i < patch.size() && i < 4; ++i)
      keys += (i ? ", " : "") + std::string("model") + patch[i]["path"].get<std::string>();
    fail(path, ": the run was started with another model config (", keys, patch.size() > 4 ? ", ..." : "",
         " differ; '/' separates keys); resume with the config it started with, or start a new run in another "
         "train.out");
  }
  load_module(ck, trainable(), path);
  if (!ck.tensors.count("optim/state"))
    fail(path, ": holds no optimizer state (a weights-only checkpoint such as init); it cannot be resumed");
  if (!ck.tensors.count("rng/torch")) fail(path, ": holds no RNG state ('rng/torch'); it cannot be resumed");
  try {
    torch::serialize::InputArchive archive;
    std::istringstream bytes(tensor_to_bytes(ck.tensors.at("optim/state")));
    archive.load_from(bytes);
    optimizer_->load(archive);
  } catch (const c10::Error& e) {
    fail(path, ": optimizer state ('optim/state') is unreadable: ", e.what_without_backtrace());
  } catch (const std::exception& e) {  // the archive reader also throws plain exceptions on garbage
    fail(path, ": optimizer state ('optim/state') is unreadable: ", e.what());
  }
  try {
    at::Generator gen = at::detail::getDefaultCPUGenerator();
    gen.set_state(ck.tensors.at("rng/torch"));
  } catch (const c10::Error& e) {
    fail(path, ": RNG state ('rng/torch') is unusable: ", e.what_without_backtrace());
  }
  step_ = ck.step();
  auto cpu = ck.metadata.find("cpu_s");
  if (cpu != ck.metadata.end()) cpu_offset_ = parse_double(cpu->second).value_or(0.0);
  cpu_start_ = process_cpu_seconds();
  auto bv = ck.metadata.find("best_val");
  if (bv != ck.metadata.end()) best_val_ = parse_double(bv->second).value_or(std::numeric_limits<double>::infinity());
  loader_.reset();  // restart the data stream at the resumed step
  log_info("train: resumed from ", path, " at step ", step_);
}

void Trainer::write_curves() const {
  // curves.png from the log itself: loss terms (20-step moving average), learning rate, validation.
  std::map<std::string, ChartSeries> terms;
  ChartSeries lr{"learning rate", {}, {}, true, -1, 0}, psnr{"masked PSNR", {}, {}, true, 0, 2},
      val{"validation loss", {}, {}, true, 0, 1};
  std::map<std::string, std::vector<double>> window;
  for (const auto& j : read_jsonl(log_->path())) {
    const double step = j.value("step", 0.0);
    if (j.contains("loss") && j["loss"].is_object()) {
      for (auto it = j["loss"].begin(); it != j["loss"].end(); ++it) {
        if (!it.value().is_number() || it.key() == "total_all_ranks") continue;
        auto& w = window[it.key()];
        w.push_back(it.value().get<double>());
        if (w.size() > 20) w.erase(w.begin());
        double sum = 0;
        for (double x : w) sum += x;
        auto& series = terms[it.key()];
        series.name = it.key();
        series.x.push_back(step), series.y.push_back(sum / w.size());
      }
      if (j.contains("lr") && j["lr"].is_number()) lr.x.push_back(step), lr.y.push_back(j["lr"].get<double>());
    }
    if (j.contains("val_psnr_masked") && j["val_psnr_masked"].is_number())
      psnr.x.push_back(step), psnr.y.push_back(j["val_psnr_masked"].get<double>());
    if (j.contains("val_loss") && j["val_loss"].is_number())
      val.x.push_back(step), val.y.push_back(j["val_loss"].get<double>());
  }
  Chart loss{"training loss terms (20-step moving average)", "step", "loss", false, {}};
  for (auto& [k, v] : terms) loss.series.push_back(v);
  write_charts((fs::path(run_dir_) / "curves.png").string(),
               {loss, Chart{"learning rate", "step", "lr", false, {lr}},
                Chart{"validation: masked PSNR of the raw render", "step", "PSNR (dB)", false, {psnr}},
                Chart{"validation loss", "step", "loss", false, {val}}});
}

void Trainer::write_log(const StepStats& s) {
  log_->write({{"step", step_},
               {"cpu_s", cpu_seconds()},
               {"step_ms", s.step_ms},
               {"lr", s.lr},
               {"loss", s.losses},
               {"time_ms", s.timings_ms},
               {"supports", s.supports},
               {"skipped", s.skipped}});
}

int Trainer::run() {
  if (step_ == 0 && writer()) checkpoints_.save("init", make_checkpoint(false));  // the untrained model
  std::signal(SIGINT, [](int) { request_stop(); });
  std::signal(SIGTERM, [](int) { request_stop(); });
  ProgressBar bar("train", config_.train.steps - step_, "step");
  std::map<std::string, double> time_sum;
  int64_t timed = 0;
  while (step_ < config_.train.steps) {
    ErrorContext context("training step ", step_ + 1, " into ", config_.train.out);
    const StepStats s = train_step();
    if (writer() && (step_ % config_.train.log_every == 0 || step_ == config_.train.steps)) write_log(s);
    for (const auto& [k, v] : s.timings_ms) time_sum[k] += v;
    ++timed;
    std::string post = cat("loss ", std::setprecision(4), s.losses.at("total"));
    for (const char* k : {"l1", "perceptual", "silog"})
      if (s.losses.count(k)) post += cat(" ", k, " ", std::setprecision(3), s.losses.at(k));
    bar.postfix(post);
    bar.tick();
    const bool periodic = step_ % config_.train.checkpoint_every == 0 || step_ == config_.train.steps;
    bool improved = false;
    if (writer() && (step_ % config_.train.val_every == 0 || step_ == config_.train.steps)) {
      const double v = validate(true);
      improved = std::isfinite(v) && v < best_val_;
      if (improved) best_val_ = v;  // before saving, so the checkpoint records it
    }
    if (periodic && writer()) checkpoints_.save_periodic(step_, make_checkpoint(true));
    if (improved) {
      if (periodic)
        checkpoints_.alias("last", "best");
      else
        checkpoints_.save("best", make_checkpoint(true));
    }
    if (config_.train.stop_at > 0 && step_ == config_.train.stop_at && step_ < config_.train.steps) {
      bar.finish();
      if (writer() && !periodic) checkpoints_.save_periodic(step_, make_checkpoint(true));
      log_info("train: stopped at step ", step_, " (train.stop_at); --resume auto continues to ", config_.train.steps);
      return 0;
    }
    if (stop_) {
      bar.finish();
      if (!writer()) return 130;
      checkpoints_.save("last", make_checkpoint(true));
      log_warn("train: interrupted; checkpoint written to ", checkpoints_.path("last"), " (resume with --resume auto)");
      return 130;
    }
  }
  bar.finish();
  if (!writer()) return 0;
  task_->finish(run_dir_);
  nlohmann::json summary = {{"steps", step_}, {"best_val_loss", best_val_}, {"commit", build_commit()}};
  for (auto& [k, v] : time_sum) summary["mean_step_time_ms"][k] = v / std::max<int64_t>(1, timed);
  write_file_atomic((fs::path(run_dir_) / "summary.json").string(), summary.dump(2) + "\n");
  std::string breakdown;
  for (auto& [k, v] : time_sum)
    breakdown += cat(" ", k, " ", std::fixed, std::setprecision(0), v / std::max<int64_t>(1, timed));
  log_info("train: done, ", step_, " steps; mean ms per step:", breakdown, "; run folder ", run_dir_);
  return 0;
}

}  // namespace isplat
