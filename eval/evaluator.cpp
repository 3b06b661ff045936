// Evaluation loop with resumable per-pair JSON-lines results.
#include "eval/evaluator.h"

#include <torch/torch.h>

#include <filesystem>
#include <regex>

#include "core/config.h"
#include "core/error.h"
#include "core/log.h"
#include "core/paths.h"
#include "core/progress.h"
#include "data/colmap.h"
#include "data/perturb.h"
#include "eval/densify.h"
#include "eval/method_stamp.h"
#include "eval/region_scores.h"
#include "eval/results_log.h"
#include "io/atomic_file.h"
#include "io/folder_lock.h"
#include "io/panel.h"
#include "metrics/display.h"
#include "metrics/mask.h"
#include "metrics/stability.h"
#include "render/scale_align.h"

namespace isplat {
namespace fs = std::filesystem;

namespace {
// Releases scoring.out's lock at the end of the scope that took it (run, or a merge and the run it ends with).
struct ReleaseLock {
  std::unique_ptr<FolderLock>& lock;
  bool mine;
  ~ReleaseLock() {
    if (mine) lock.reset();
  }
};
}  // namespace

Evaluator::Evaluator(EvalConfig config) : config_(std::move(config)) {
  check_dataset_names(config_.datasets);
  config_.methods = expand_sweeps(config_.methods);
  for (const auto& net : config_.scoring.lpips) {
    std::string why;
    auto lp = Lpips::from_folder(net, config_.scoring.weights_dir, why);
    if (lp) {
      lpips_[net] = std::move(lp);
    } else {
      const std::string note = cat("LPIPS (", net, ") is n/a: ", why, " (config key scoring.weights_dir)");
      log_warn("eval: ", note);
      notes_.push_back(note);
    }
  }
}

Manifest Evaluator::manifest(size_t d, const std::vector<Sequence>& sequences, const std::vector<ColmapModel>& models) {
  const auto& ds = config_.datasets[d];
  const std::string path = (fs::path(dataset_dir(d)) / "manifest.json").string();
  const nlohmann::json fingerprint = dataset_fingerprint(ds, sequences);
  if (fs::exists(path)) {
    Manifest m = read_manifest(path);
    // Scores are found by dataset name: data that changed under the same name never reuses them.
    if (m.dataset_fingerprint.is_null()) {
      log_info("eval: ", ds.name, ": ", path, " predates dataset fingerprints; it adopts the data at ", ds.root);
      m.dataset_fingerprint = fingerprint;
      write_manifest(path, m);
    }
    if (const std::string changes = fingerprint_changes(m.dataset_fingerprint, fingerprint); !changes.empty())
      fail("eval: dataset '", ds.name, "' changed since ", path, " and the scores beside it were made: ", changes,
           ". Its old scores are not reused: choose another scoring.out or dataset name, or delete ", dataset_dir(d),
           " to score it again");
    if (config_to_json(m.protocol) == config_to_json(config_.protocol)) {
      log_info("eval: ", ds.name, ": reusing ", path, " (", m.pairs.size(), " pairs)");
      return m;
    }
    log_info("eval: ", ds.name, ": protocol changed; drawing a new manifest");
  } else if (fs::is_directory(dataset_dir(d))) {
    // No manifest, but results may be there (the manifest was deleted): their stamps know the data they were scored
    // on, checked before a manifest of other data is written beside them.
    for (const auto& e : fs::directory_iterator(dataset_dir(d))) {
      const std::string name = e.path().filename().string();
      if (name.size() < 12 || name.compare(name.size() - 12, 12, ".method.json") != 0) continue;
      const nlohmann::json stamp = read_json_file(e.path().string());
      if (!stamp.is_object() || !stamp.contains("dataset_fingerprint")) continue;
      if (const std::string changes = fingerprint_changes(stamp["dataset_fingerprint"], fingerprint); !changes.empty())
        fail("eval: dataset '", ds.name, "' changed since the scores in ", dataset_dir(d), " were made (",
             e.path().string(), "): ", changes,
             ". Its old scores are not reused: choose another scoring.out or dataset name, or delete ", dataset_dir(d),
             " to score it again");
    }
  }
  Manifest m = draw_manifest(ds.name, sequences, config_.protocol, models);
  m.dataset_fingerprint = fingerprint;
  write_manifest(path, m);
  log_info("eval: ", ds.name, ": ", m.pairs.size(), " pairs -> ", path);
  return m;
}

namespace {
bool dataset_has_depth(const std::vector<Sequence>& sequences) {
  for (const auto& s : sequences)
    for (const auto& f : s.frames)
      if (f.depth != DepthSource::None) return true;
  return false;
}

// COLMAP points3D seen by the source frame as sparse prompts [P,3] (u, v, z) at evaluation size, or
// undefined when fewer than 3 fall inside the image (then the source depth is used).
torch::Tensor points3d_prompts(const ColmapModel& model, const LoadedFrame& frame, const ViewTensors& src) {
  const auto native = colmap_sparse_depth(model, frame.view);
  const View ev = to_view(src.camera);
  auto t = torch::empty({static_cast<int64_t>(native.size()), 3});
  int64_t k = 0;
  for (const auto& q : native) {
    const Eigen::Vector3d X = frame.view.intr.backproject(q.x(), q.y(), q.z());
    const Eigen::Vector2d uv = ev.intr.project(X);
    if (uv.x() < 0 || uv.y() < 0 || uv.x() >= ev.intr.width || uv.y() >= ev.intr.height) continue;
    t[k][0] = uv.x(), t[k][1] = uv.y(), t[k][2] = q.z();
    ++k;
  }
  return k < 3 ? torch::Tensor() : t.narrow(0, 0, k);
}
}  // namespace

const std::vector<ColmapModel>& Evaluator::alignment_points(size_t d) {
  auto it = align_models_.find(d);
  if (it != align_models_.end()) return it->second;
  const auto& ds = config_.datasets.at(d);
  ISPLAT_CHECK(ds.format == "colmap", "eval: scoring.align_scale = points needs COLMAP points3D, but dataset '",
               ds.name, "' has format ", ds.format, " (use align_scale = depth where the dataset has depth)");
  return align_models_[d] = load_eval_points3d(ds);
}

std::vector<int64_t> Evaluator::select_pairs(const Manifest& m) const {
  std::vector<int64_t> pairs;
  std::map<int, int64_t> per_bin;
  int64_t position = 0;
  for (int64_t i = 0; i < static_cast<int64_t>(m.pairs.size()); ++i)  // the manifest's order is already random
    if (config_.scoring.max_per_bin <= 0 || per_bin[m.pairs[i].bin]++ < config_.scoring.max_per_bin)
      if (position++ % shard_count_ == shard_index_) pairs.push_back(i);
  return pairs;
}

void Evaluator::set_shard(int64_t index, int64_t count) {
  ISPLAT_CHECK(count >= 1 && index >= 0 && index < count, "eval: shard ", index, "/", count,
               " is not one of 0/N .. N-1/N (--shard i/n)");
  shard_index_ = index, shard_count_ = count;
}

std::string Evaluator::dataset_dir(size_t d) const {
  return (fs::path(config_.scoring.out) / safe_name(config_.datasets.at(d).name)).string();
}

std::string Evaluator::results_path(size_t d, const std::string& method) const {
  const std::string shard = shard_count_ > 1 ? cat(".shard-", shard_index_, "-of-", shard_count_) : std::string();
  return (fs::path(dataset_dir(d)) / ("results_" + safe_name(method) + shard + ".jsonl")).string();
}

std::vector<ReportRow> Evaluator::merge(int64_t count) {
  ISPLAT_CHECK(count >= 1, "eval: --merge needs the shard count");
  const ReleaseLock release{lock_, !lock_};
  lock_output();
  for (size_t d = 0; d < config_.datasets.size(); ++d) {
    const auto& ds = config_.datasets[d];
    const std::string manifest_path = (fs::path(dataset_dir(d)) / "manifest.json").string();
    ISPLAT_CHECK(fs::exists(manifest_path), "eval --merge: ", manifest_path, " is missing; run the shards first");
    const Manifest m = read_manifest(manifest_path);
    set_shard(0, 1);
    const std::vector<int64_t> all = select_pairs(m);
    for (const auto& mo : config_.methods) {
      std::map<int64_t, PairResult> merged;
      for (int64_t k = 0; k < count; ++k) {
        set_shard(k, count);
        const std::string path = results_path(d, mo.label());
        ISPLAT_CHECK(fs::exists(path), "eval --merge: shard ", k, "/", count, " has no results for ", ds.name, " / ",
                     mo.label(), " (", path, ")");
        check_method_stamp(path, mo, config_.scoring, m.dataset_fingerprint);  // scored as this config says
        const ResultsLog shard(path);
        for (int64_t i : select_pairs(m)) {
          auto it = shard.done().find(i);
          ISPLAT_CHECK(it != shard.done().end(), "eval --merge: ", path, " lacks pair ", i,
                       " (that shard did not finish; rerun it)");
          merged.emplace(i, it->second);
        }
      }
      set_shard(0, 1);
      check_method_stamp(results_path(d, mo.label()), mo, config_.scoring, m.dataset_fingerprint);
      ISPLAT_CHECK(merged.size() == all.size(), "eval --merge: ", ds.name, " / ", mo.label(), ": ", merged.size(),
                   " pairs from the shards, the manifest selects ", all.size());
      // Rewritten whole, in manifest order, so the merged file equals an unsharded run's.
      std::ostringstream out;
      for (int64_t i : all) out << result_json(merged.at(i)).dump() << "\n";
      write_file_atomic(results_path(d, mo.label()), out.str());
    }
  }
  set_shard(0, 1);
  return run();
}

std::string pair_motion(const ViewTensors& src, const ViewTensors& tgt, const torch::Tensor& prompts) {
  const auto Ts = src.camera.T_cw.to(torch::kFloat64), Tt = tgt.camera.T_cw.to(torch::kFloat64);
  const auto Rt = Tt.slice(0, 0, 3).slice(1, 0, 3), tt = Tt.slice(0, 0, 3).select(1, 3);
  const auto centre = -torch::matmul(Rt.t(), tt);
  const auto in_source = torch::matmul(Ts.slice(0, 0, 3).slice(1, 0, 3), centre) + Ts.slice(0, 0, 3).select(1, 3);
  const auto axis_s = Ts.select(0, 2).slice(0, 0, 3), axis_t = Tt.select(0, 2).slice(0, 0, 3);
  const double cosang = std::clamp(torch::dot(axis_s, axis_t).item<double>(), -1.0, 1.0);
  torch::Tensor z =
      src.depth.defined() && src.valid.defined() ? src.depth.masked_select(src.valid > 0) : torch::Tensor();
  if ((!z.defined() || z.numel() == 0) && prompts.defined() && prompts.numel() > 0) z = prompts.select(1, 2);
  if (!z.defined() || z.numel() == 0) return "";  // no depth at all: the motion type is unknown
  const double median = z.median().item<double>();
  if (!(median > 0)) return "";
  const double half_edge = static_cast<double>(src.image.size(2)) / 4.0 / src.camera.K[0][0].item<double>();
  return motion_type({in_source[0].item<double>(), in_source[1].item<double>(), in_source[2].item<double>()},
                     std::acos(cosang) * 180.0 / M_PI, median, half_edge);
}

// The target's reference depth for the stability measures (0 where invalid), or undefined when it has none.
static torch::Tensor reference_depth(const ViewTensors& view) {
  if (!view.valid.defined() || !(view.valid.sum().item<double>() > 0)) return {};
  return view.depth * (view.valid > 0);
}

// The depth sum the crack measures divide by alpha: the render's, or with scoring.crack_depth = median the median
// depth times alpha (so the division gives the median back).
static torch::Tensor crack_depth_sum(const MethodOutput& o, const std::string& crack_depth) {
  if (crack_depth == "mean") return o.depth;
  ISPLAT_CHECK(o.median_depth.defined(), "eval: scoring.crack_depth = median, but the method rendered no median depth");
  return o.median_depth * o.alpha;
}

RenderMaps Evaluator::scoring_maps() const {
  RenderMaps maps;
  maps.median_depth = config_.scoring.crack_depth == "median";
  return maps;
}

StabilityOptions Evaluator::crack_options() const {
  StabilityOptions so;
  so.edge_margin = config_.scoring.crack_edge_margin;
  so.holes_break = config_.scoring.crack_holes;
  so.crack_side = parse_crack_side(config_.scoring.crack_side);
  so.min_error = config_.scoring.crack_min_error;
  so.edge_side = parse_edge_side(config_.scoring.crack_edge_side);
  return so;
}

DisplayScore Evaluator::score_display(const MethodOutput& o, const ViewTensors& tgt, const torch::Tensor& mask,
                                      double factor) const {
  const Camera camera = upscaled_camera(tgt.camera, factor);
  const RenderOutput r = render(o.scene, camera, config_.scoring.render, RenderMaps::colour_only());
  const auto target = resize_bilinear(tgt.image.unsqueeze(0), camera.height, camera.width).squeeze(0);
  const auto big_mask = (resize_bilinear(mask.view({1, 1, mask.size(0), mask.size(1)}).to(torch::kFloat32),
                                         camera.height, camera.width) >= 0.5)
                            .to(torch::kFloat32)
                            .view({camera.height, camera.width});
  return {factor, psnr(rendered_srgb(r.rgb, o.linear_rgb), target, big_mask), hole_rate(r.alpha, big_mask)};
}

ScoredPair Evaluator::score_pair(size_t d, const std::vector<Sequence>& sequences, const Manifest& m, int64_t i,
                                 const MethodOptions& mo, Method& method, const std::vector<ColmapModel>& points,
                                 bool has_depth) {
  const auto& ds = config_.datasets[d];
  ISPLAT_CHECK(i >= 0 && i < static_cast<int64_t>(m.pairs.size()), "eval: pair ", i, " is not in the manifest of ",
               ds.name);
  const Pair& p = m.pairs[static_cast<size_t>(i)];
  ErrorContext context("scoring method '", mo.name, "' on pair ", i, " of dataset '", ds.name, "'");
  ISPLAT_CHECK(p.sequence_index < sequences.size(), "eval: manifest pair ", i, " names sequence ", p.sequence_index,
               " but the dataset has ", sequences.size(), " (re-draw the manifest)");
  const Sequence& seq = sequences[p.sequence_index];
  const LoadedFrame sf = load_frame(seq, p.source), tf = load_frame(seq, p.target, /*with_depth=*/has_depth);
  const int64_t W = ds.width ? ds.width : sf.image.cols, H = ds.height ? ds.height : sf.image.rows;
  const ViewTensors src = make_view_tensors(sf, p.source_name, W, H);
  const ViewTensors tgt = make_view_tensors(tf, p.target_name, W, H);
  const torch::Tensor prompts =
      points.empty() ? torch::Tensor() : points3d_prompts(points.at(p.sequence_index), sf, src);
  const ViewTensors seen = perturb_source(src, mo.perturb, static_cast<uint64_t>(i));
  // Without reference depth the paper scores the whole frame; with it, where the source projects. The mask comes
  // from the unperturbed source (a perturbation never changes which pixels are scored) unless scoring.mask_depth =
  // seen asks for the depth the method saw.
  const ViewTensors& masked = config_.scoring.mask_depth == "seen" && seen.valid.defined() ? seen : src;
  const torch::Tensor mask = masked.valid.sum().item<double>() > 0
                                 ? projected_mask(masked.depth, masked.valid, to_view(src.camera), to_view(tgt.camera),
                                                  static_cast<int>(config_.scoring.mask_radius))
                                 : torch::ones({H, W});
  AlignScene align;  // scoring.align_scale: the same fit on the same reference samples for every method
  if (config_.scoring.align_scale != "none") {
    const torch::Tensor samples = config_.scoring.align_scale == "depth"
                                      ? depth_samples(src.depth, src.valid)
                                      : points3d_prompts(alignment_points(d).at(p.sequence_index), sf, src);
    align = [&, samples](Gaussians& g) {
      const ScaleFit fit = fit_scene_scale(g, src.camera, samples, config_.scoring.render);
      g = scale_about_camera(g, src.camera, fit.factor);
      return fit;
    };
  }
  const MethodOutput o = method.predict(seen, tgt.camera, static_cast<uint64_t>(i),
                                        perturb_prompts(prompts, mo.perturb, static_cast<uint64_t>(i), W, H), align);
  PairResult r;
  r.index = i;
  r.bin = p.bin;
  r.baseline = p.baseline;
  r.rotation_deg = p.rotation_deg;
  r.motion = pair_motion(src, tgt, prompts);
  r.mask_fraction = mask.mean().item<double>();
  r.psnr = psnr(o.image, tgt.image, mask);
  r.ssim = ssim(o.image, tgt.image, mask);
  for (const auto& net : config_.scoring.lpips) {
    auto it = lpips_.find(net);
    r.lpips[net] =
        it == lpips_.end() ? std::numeric_limits<double>::quiet_NaN() : (*it->second)(o.image, tgt.image, mask);
  }
  r.infer_ms = o.infer_ms;
  r.render_ms = o.render_ms;
  r.gaussians = o.gaussians;
  r.decoded = o.decoded;
  r.stage_ms = o.stage_ms;
  r.prune_counts = o.prune_counts;
  r.peak_mb = o.peak_mb;
  r.work_mb = o.work_mb;
  if (o.alpha.defined()) {
    r.hole_rate = hole_rate(o.alpha, mask);
    if (const auto ref = reference_depth(tgt); ref.defined()) {
      r.crack_rate = crack_rate(crack_depth_sum(o, config_.scoring.crack_depth), o.alpha, ref, mask, crack_options());
      r.normal_deg = normal_incoherence_deg(o.normal, o.alpha, ref, tgt.camera.K, mask);
    }
  }
  if (o.aligned) r.scale = o.scale.factor, r.scale_samples = o.scale.samples;
  if (o.densified.defined() && src.valid.defined()) {
    const DensifyScores ds_scores = score_densification(o.densified, o.prompt_pixels, src.depth, src.valid,
                                                        seen.valid.defined() ? seen.valid : src.valid);
    r.unprompted = ds_scores.unprompted, r.removed = ds_scores.removed;
  }
  if (o.scene.means.defined())
    for (double factor : config_.scoring.display_factors) r.display.push_back(score_display(o, tgt, mask, factor));
  if (config_.scoring.regions) {
    const Lpips* first = nullptr;
    for (const auto& net : config_.scoring.lpips)
      if (auto it = lpips_.find(net); !first && it != lpips_.end()) first = it->second.get();
    score_regions(o, src, tgt, mask, reference_depth(tgt), first, config_.scoring.render, r);
  }
  return {r, src, tgt, mask, o};
}

std::vector<PairResult> Evaluator::score(size_t d, const std::vector<Sequence>& sequences, const Manifest& m,
                                         const std::vector<int64_t>& pairs, const MethodOptions& mo,
                                         const std::vector<ColmapModel>& points) {
  const auto& ds = config_.datasets[d];
  const fs::path dir = dataset_dir(d);
  const bool has_depth = dataset_has_depth(sequences);
  check_method_stamp(results_path(d, mo.label()), mo, config_.scoring, m.dataset_fingerprint);
  ResultsLog log(
      results_path(d, mo.label()), [&](const PairResult& r) { return check_against_manifest(r, m); }, mo.id());
  std::vector<int64_t> todo;
  for (int64_t i : pairs)
    if (!log.done().count(i)) todo.push_back(i);
  if (!todo.empty()) {
    auto method = make_method(mo, config_.scoring.render, scoring_maps());
    if (!has_depth && method->needs_source_depth(!points.empty())) {
      notes_.push_back(cat(ds.name, " / ", mo.label(),
                           ": not scored; the method needs the source depth and the dataset "
                           "has none (",
                           method->describe(), ")"));
      log_warn("eval: ", notes_.back());
      return {};
    }
    log_info("eval: ", ds.name, " / ", mo.label(), " (", method->describe(), "): ", todo.size(), " pairs to score",
             todo.size() == pairs.size() ? "" : cat(", ", pairs.size() - todo.size(), " resumed"));
    ProgressBar bar(cat("eval ", ds.name, "/", mo.label()), static_cast<int64_t>(todo.size()), "pair");
    int64_t examples = 0;
    for (int64_t i : todo) {
      const ScoredPair sp = score_pair(d, sequences, m, i, mo, *method, points, has_depth);
      const PairResult& r = sp.result;
      log.append(r);
      if (examples++ < config_.scoring.examples)
        write_panel((dir / "examples" / cat(safe_name(mo.label()), "_pair", i, ".png")).string(),
                    {{sp.source.image, sp.target.image, outline_mask(sp.output.image, sp.mask), sp.mask.unsqueeze(0)}});
      bar.postfix(cat("PSNR ", std::setprecision(3), r.psnr));
      bar.tick();
    }
    bar.finish();
  } else {
    log_info("eval: ", ds.name, " / ", mo.label(), ": all ", pairs.size(), " pairs already scored");
  }
  std::vector<PairResult> results;
  for (int64_t i : pairs) results.push_back(log.done().at(i));
  if (config_.scoring.gallery > 0 && shard_count_ == 1) write_gallery(d, sequences, m, results, mo, points, has_depth);
  return results;
}

std::string gallery_panel_method(const std::string& file) {
  // "<method>_worst_<kind><k>_pair<i>.png": the tail holds no "_worst_", so the last one splits the name.
  static const std::regex panel(R"((.+)_worst_(psnr|holes|cracks)[0-9]+_pair[0-9]+\.png)");
  std::smatch m;
  return std::regex_match(file, m, panel) ? m[1].str() : std::string();
}

void Evaluator::lock_output() {
  if (lock_) return;
  // Shards write their own results files and may run at once; an unsharded run or a merge owns the folder.
  const std::string name = shard_count_ > 1 ? cat(".lock-shard-", shard_index_, "-of-", shard_count_) : ".lock";
  try {
    lock_ = std::make_unique<FolderLock>(config_.scoring.out, name);
  } catch (const Error& e) {
    fail("eval: scoring.out ", config_.scoring.out, ": ", e.what());
  }
}

void Evaluator::write_gallery(size_t d, const std::vector<Sequence>& sequences, const Manifest& m,
                              const std::vector<PairResult>& results, const MethodOptions& mo,
                              const std::vector<ColmapModel>& points, bool has_depth) {
  std::vector<const PairResult*> by_psnr, by_holes, by_cracks;
  for (const auto& r : results) {
    if (std::isfinite(r.psnr)) by_psnr.push_back(&r);
    if (std::isfinite(r.hole_rate) && r.hole_rate > 0) by_holes.push_back(&r);
    if (std::isfinite(r.crack_rate) && r.crack_rate > 0) by_cracks.push_back(&r);
  }
  std::stable_sort(by_psnr.begin(), by_psnr.end(), [](auto* a, auto* b) { return a->psnr < b->psnr; });
  std::stable_sort(by_holes.begin(), by_holes.end(), [](auto* a, auto* b) { return a->hole_rate > b->hole_rate; });
  std::stable_sort(by_cracks.begin(), by_cracks.end(), [](auto* a, auto* b) { return a->crack_rate > b->crack_rate; });
  const fs::path dir = fs::path(dataset_dir(d)) / "gallery";
  std::vector<std::pair<fs::path, int64_t>> wanted;
  for (size_t k = 0; k < static_cast<size_t>(config_.scoring.gallery); ++k)
    for (const auto& [kind, worst] : {std::pair{"psnr", &by_psnr}, {"holes", &by_holes}, {"cracks", &by_cracks}})
      if (k < worst->size())
        wanted.push_back({dir / cat(safe_name(mo.label()), "_worst_", kind, k + 1, "_pair", (*worst)[k]->index, ".png"),
                          (*worst)[k]->index});
  // Panels of this method's pairs that are no longer among the worst (the results changed) go: only names that are
  // exactly this method's panel names (another method's, e.g. "m_worst_a" beside "m", share their start).
  if (fs::exists(dir))
    for (const auto& e : fs::directory_iterator(dir)) {
      if (gallery_panel_method(e.path().filename().string()) == safe_name(mo.label()) &&
          std::none_of(wanted.begin(), wanted.end(), [&](const auto& w) { return w.first == e.path(); }))
        fs::remove(e.path());
    }
  std::unique_ptr<Method> method;
  for (const auto& [path, i] : wanted) {
    if (fs::exists(path)) continue;
    if (!method) method = make_method(mo, config_.scoring.render, scoring_maps());
    const ScoredPair sp = score_pair(d, sequences, m, i, mo, *method, points, has_depth);
    const auto& o = sp.output;
    const int64_t H = sp.mask.size(0), W = sp.mask.size(1);
    // |error| x4 inside the scored mask (outside it the prediction is not judged)
    const auto error = torch::clamp(4 * (o.image - sp.target.image).abs().mean(0, true), 0.0, 1.0) * sp.mask;
    const auto normals =
        o.normal.defined()
            ? (torch::nn::functional::normalize(o.normal, torch::nn::functional::NormalizeFuncOptions().dim(0)) + 1) / 2
            : torch::zeros({3, H, W});
    const auto alpha = o.alpha.defined() ? o.alpha.reshape({1, H, W}) : torch::zeros({1, H, W});
    std::vector<torch::Tensor> row = {sp.source.image, sp.target.image, outline_mask(o.image, sp.mask),
                                      error,           normals,         alpha};
    if (const auto ref = reference_depth(sp.target); o.alpha.defined() && ref.defined())
      row.push_back(crack_map(crack_depth_sum(o, config_.scoring.crack_depth), o.alpha, ref, sp.mask, crack_options()));
    write_panel(path.string(), {row});
  }
  if (!wanted.empty())
    log_info("eval: failure gallery of ", config_.datasets[d].name, " / ", mo.label(), " in ", dir.string());
}

std::vector<ReportRow> Evaluator::run(bool pairs_only) {
  const ReleaseLock release{lock_, !lock_};
  lock_output();
  write_file_atomic((fs::path(config_.scoring.out) / "config.json").string(), config_to_json(config_).dump(2) + "\n");
  const std::vector<std::string>& nets = config_.scoring.lpips;
  std::vector<ReportRow> rows;
  std::vector<DiffRow> differences;
  std::vector<SweepSlope> slopes;
  std::vector<ReportRow> breakdowns;
  if (config_.scoring.max_per_bin > 0)
    notes_.push_back(cat("only the first ", config_.scoring.max_per_bin,
                         " pairs of each bin were scored "
                         "(scoring.max_per_bin); the full protocol scores every pair of the manifest"));
  if (config_.scoring.crack_edge_margin > 0)
    notes_.push_back(cat("cracks skip neighbour pairs within ", config_.scoring.crack_edge_margin,
                         " px of a reference depth edge (scoring.crack_edge_margin): tears in surfaces only"));
  if (config_.scoring.crack_holes)
    notes_.push_back(
        "cracks count smooth neighbour pairs with a hole on either side as broken "
        "(scoring.crack_holes): holes and jumps together");
  if (config_.scoring.crack_min_error > 0)
    notes_.push_back(cat("cracks count only breaks whose deviant pixel errs by at least ",
                         config_.scoring.crack_min_error, " of the reference depth (scoring.crack_min_error)"));
  if (config_.scoring.crack_edge_side != "any")
    notes_.push_back(cat("cracks count only breaks whose deviant pixel lies on the ", config_.scoring.crack_edge_side,
                         " side of a reference depth edge within 2 px (scoring.crack_edge_side)"));
  if (config_.scoring.crack_depth != "mean")
    notes_.push_back(
        "cracks compare each pixel's median rendered depth, the surface it shows (scoring.crack_depth = median), "
        "not the mean of the surfaces it blends; render times include the median depth's extra pass");
  if (config_.scoring.crack_side != "any")
    notes_.push_back(cat("cracks count only broken pairs that err ", config_.scoring.crack_side,
                         " than the reference depth (scoring.crack_side)"));
  // Every checkpoint must exist before anything is scored: a typo or a row still training must not surface an hour
  // into a run.
  if (!pairs_only)
    for (const auto& mo : config_.methods) {
      ISPLAT_CHECK(mo.checkpoint.empty() || fs::is_regular_file(mo.checkpoint), "eval: method '", mo.name,
                   "': checkpoint ", mo.checkpoint, ": no such file (nothing was scored)");
      // A training run's checkpoints/ folder: without summary.json the run is still training (or was stopped), so
      // last.safetensors is an intermediate step that will change under the same name.
      const fs::path folder = fs::path(mo.checkpoint).parent_path(), run = folder.parent_path();
      if (!mo.checkpoint.empty() && folder.filename() == "checkpoints" && fs::exists(run / "config.json") &&
          !fs::exists(run / "summary.json")) {
        notes_.push_back(cat(mo.name, ": ", mo.checkpoint, " is from a run that has not finished (", run.string(),
                             " has no summary.json): its scores are of an intermediate step"));
        log_warn("eval: ", notes_.back());
      }
    }
  for (size_t d = 0; d < config_.datasets.size(); ++d) {
    const auto& ds = config_.datasets[d];
    const auto sequences = load_eval_dataset(ds);
    const bool has_depth = dataset_has_depth(sequences);
    // COLMAP points3D: prompts for LiDAR variants, and the overlap depth of captures without depth.
    const std::vector<ColmapModel> models = ds.format == "colmap" && (ds.prompts == "points3d" || !has_depth)
                                                ? load_eval_points3d(ds)
                                                : std::vector<ColmapModel>{};
    const Manifest m = manifest(d, sequences, models);
    ISPLAT_CHECK(config_.scoring.align_scale != "depth" || has_depth,
                 "eval: scoring.align_scale = depth, but dataset '", ds.name,
                 "' has no depth (use align_scale = points with its COLMAP points3D)");
    if (config_.scoring.align_scale != "none")
      notes_.push_back(cat(ds.name,
                           ": every prediction was scaled to the dataset before rendering (scoring.align_scale"
                           " = ",
                           config_.scoring.align_scale, "); baseline bins are in the dataset's units"));
    if (!has_depth)
      notes_.push_back(cat(ds.name,
                           ": no reference depth, so masks are the full frame (the paper masks only where "
                           "reference depth exists); pair overlap used ",
                           nlohmann::json(m.overlap_depth).dump(), " (protocol.fallback_depth)"));
    std::vector<std::string> labels;
    for (size_t b = 0; b < m.bin_counts.size(); ++b) {
      labels.push_back(m.bin_label(static_cast<int>(b)));
      if (m.bin_counts[b] < config_.protocol.pairs_per_bin)
        notes_.push_back(cat(ds.name, ": bin ", labels.back(), " has ", m.bin_counts[b], " of ",
                             config_.protocol.pairs_per_bin, " pairs; it is not padded. ",
                             m.shortfall_reason(static_cast<int>(b))));
    }
    if (pairs_only) continue;
    std::vector<int64_t> requested(m.bin_counts.size(), config_.protocol.pairs_per_bin);
    const std::vector<ColmapModel> no_points;
    const std::vector<ColmapModel>& points = ds.prompts == "points3d" ? models : no_points;
    const std::vector<int64_t> pairs = select_pairs(m);
    ScoredMethods by_method;
    for (const auto& mo : config_.methods) {
      auto results = score(d, sequences, m, pairs, mo, points);
      if (results.empty() && !pairs.empty()) continue;  // not applicable here; score() left a note
      auto r = summarize(ds.name, mo.id(), labels, requested, results, nets);
      rows.insert(rows.end(), r.begin(), r.end());
      auto b = breakdown(ds.name, mo.id(), results, nets, config_.scoring.baseline_step);
      breakdowns.insert(breakdowns.end(), b.begin(), b.end());
      by_method[mo.id()] = std::move(results);
    }
    if (!config_.scoring.reference.empty()) {
      auto diffs =
          paired_differences(ds.name, config_.scoring.reference, by_method, nets.empty() ? "" : nets[0], 2000, labels);
      differences.insert(differences.end(), diffs.begin(), diffs.end());
    }
    const auto sl = sweep_slopes(ds.name, by_method);
    slopes.insert(slopes.end(), sl.begin(), sl.end());
  }
  if (shard_count_ > 1) {
    log_info("eval: shard ", shard_index_, "/", shard_count_, " scored; combine the shards with --merge ",
             shard_count_);
    return rows;
  }
  if (!pairs_only) {
    write_reports(config_.scoring.out, rows, nets, notes_, differences, breakdowns, slopes);
    log_info("eval: reports in ", config_.scoring.out, " (report.md, report.csv, report.json, speed_quality.png)");
  }
  return rows;
}

}  // namespace isplat
