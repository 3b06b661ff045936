// Evaluation loop with resumable per-pair JSON-lines results.
#include "eval/evaluator.h"

#include <torch/torch.h>

#include <filesystem>
#include <fstream>
#include <set>

#include "core/config.h"
#include "core/error.h"
#include "core/log.h"
#include "core/progress.h"
#include "data/colmap.h"
#include "io/atomic_file.h"
#include "io/image_io.h"
#include "io/tensor_image.h"
#include "metrics/mask.h"

namespace isplat {
namespace fs = std::filesystem;

Evaluator::Evaluator(EvalConfig config) : config_(std::move(config)) {
  ISPLAT_CHECK(!config_.datasets.empty(), "eval: no datasets (config key datasets)");
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

Manifest Evaluator::manifest(size_t d, const std::vector<Sequence>& sequences) {
  const auto& ds = config_.datasets[d];
  const std::string path = (fs::path(config_.scoring.out) / ds.name / "manifest.json").string();
  if (fs::exists(path)) {
    Manifest m = read_manifest(path);
    if (config_to_json(m.protocol) == config_to_json(config_.protocol)) {
      log_info("eval: ", ds.name, ": reusing ", path, " (", m.pairs.size(), " pairs)");
      return m;
    }
    log_info("eval: ", ds.name, ": protocol changed; drawing a new manifest");
  }
  Manifest m = select_pairs(ds.name, sequences, config_.protocol);
  write_manifest(path, m);
  log_info("eval: ", ds.name, ": ", m.pairs.size(), " pairs -> ", path);
  return m;
}

namespace {
nlohmann::json result_json(const PairResult& r) {
  nlohmann::json j = {{"index", r.index},
                      {"bin", r.bin},
                      {"baseline", r.baseline},
                      {"psnr", std::isfinite(r.psnr) ? nlohmann::json(r.psnr) : nlohmann::json(nullptr)},
                      {"ssim", r.ssim},
                      {"infer_ms", r.infer_ms},
                      {"render_ms", r.render_ms},
                      {"gaussians", r.gaussians},
                      {"mask_fraction", r.mask_fraction}};
  for (const auto& [k, v] : r.lpips) j["lpips_" + k] = std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
  return j;
}

PairResult result_from_json(const nlohmann::json& j) {
  PairResult r;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  r.index = j.at("index").get<int64_t>();
  r.bin = j.at("bin").get<int>();
  r.baseline = j.at("baseline").get<double>();
  r.psnr = j.at("psnr").is_null() ? std::numeric_limits<double>::infinity() : j.at("psnr").get<double>();
  r.ssim = j.at("ssim").get<double>();
  r.infer_ms = j.at("infer_ms").get<double>();
  r.render_ms = j.at("render_ms").get<double>();
  r.gaussians = j.at("gaussians").get<int64_t>();
  r.mask_fraction = j.at("mask_fraction").get<double>();
  for (auto it = j.begin(); it != j.end(); ++it)
    if (it.key().rfind("lpips_", 0) == 0)
      r.lpips[it.key().substr(6)] = it.value().is_null() ? nan : it.value().get<double>();
  return r;
}

std::string safe(const std::string& s) {
  std::string o = s;
  for (char& c : o)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_') c = '_';
  return o;
}
}  // namespace

std::vector<PairResult> Evaluator::score(size_t d, const std::vector<Sequence>& sequences, const Manifest& m,
                                         const MethodOptions& mo, const std::vector<ColmapModel>& points) {
  const auto& ds = config_.datasets[d];
  const fs::path dir = fs::path(config_.scoring.out) / ds.name;
  const std::string results_path = (dir / ("results_" + safe(mo.name) + ".jsonl")).string();
  std::vector<PairResult> results;
  std::set<int64_t> done;
  if (fs::exists(results_path)) {  // resume: keep finished pairs
    std::ifstream in(results_path);
    std::string line;
    int64_t lineno = 0;
    while (std::getline(in, line)) {
      ++lineno;
      if (line.empty()) continue;
      try {
        PairResult r = result_from_json(nlohmann::json::parse(line));
        if (done.insert(r.index).second) results.push_back(r);
      } catch (const std::exception& e) {
        log_warn("eval: ", results_path, ":", lineno, " is unreadable (", e.what(), "); that pair is scored again");
      }
    }
  }
  // The pairs to score: all, or the first max_per_bin of each bin (the manifest's order is already random).
  const int64_t n = static_cast<int64_t>(m.pairs.size());
  std::vector<char> wanted(static_cast<size_t>(n), 1);
  if (config_.scoring.max_per_bin > 0) {
    std::map<int, int64_t> per_bin;
    for (int64_t i = 0; i < n; ++i) wanted[i] = per_bin[m.pairs[i].bin]++ < config_.scoring.max_per_bin;
  }
  results.erase(std::remove_if(results.begin(), results.end(),
                               [&](const PairResult& r) { return r.index >= n || !wanted[r.index]; }),
                results.end());
  int64_t todo = 0;
  for (int64_t i = 0; i < n; ++i) todo += wanted[i] && !done.count(i);
  if (todo == 0) {
    log_info("eval: ", ds.name, " / ", mo.name, ": all ", n, " pairs already scored");
    return results;
  }
  auto method = make_method(mo, config_.scoring.render);
  log_info("eval: ", ds.name, " / ", mo.name, " (", method->describe(), "): ", todo, " pairs to score",
           done.empty() ? "" : cat(", ", done.size(), " resumed"));
  std::ofstream out(results_path, std::ios::app);
  ProgressBar bar(cat("eval ", ds.name, "/", mo.name), todo, "pair");
  int64_t examples = 0;
  for (int64_t i = 0; i < n; ++i) {
    if (!wanted[i] || done.count(i)) continue;
    const Pair& p = m.pairs[static_cast<size_t>(i)];
    ISPLAT_CHECK(p.sequence_index < sequences.size(), "eval: manifest pair ", i, " names sequence ", p.sequence_index,
                 " but the dataset has ", sequences.size(), " (re-draw the manifest)");
    const Sequence& seq = sequences[p.sequence_index];
    const int64_t W = ds.width, H = ds.height;
    const LoadedFrame sf = load_frame(seq, p.source), tf = load_frame(seq, p.target, /*with_depth=*/false);
    const ViewTensors src = make_view_tensors(sf, p.source_name, W ? W : sf.image.cols, H ? H : sf.image.rows);
    const ViewTensors tgt = make_view_tensors(tf, p.target_name, W ? W : sf.image.cols, H ? H : sf.image.rows);
    const torch::Tensor mask = projected_mask(src.depth, src.valid, to_view(src.camera), to_view(tgt.camera),
                                              static_cast<int>(config_.scoring.mask_radius));
    torch::Tensor prompts;
    if (!points.empty()) {
      // COLMAP points3D as sparse prompts, projected at native resolution, then scaled like the image.
      const auto native = colmap_sparse_depth(points.at(p.sequence_index), sf.view);
      const View ev = to_view(src.camera);
      auto t = torch::empty({static_cast<int64_t>(native.size()), 3});
      int64_t k = 0;
      for (const auto& q : native) {
        const Eigen::Vector3d X = sf.view.intr.backproject(q.x(), q.y(), q.z());
        const Eigen::Vector2d uv = ev.intr.project(X);
        if (uv.x() < 0 || uv.y() < 0 || uv.x() >= ev.intr.width || uv.y() >= ev.intr.height) continue;
        t[k][0] = uv.x(), t[k][1] = uv.y(), t[k][2] = q.z();
        ++k;
      }
      prompts = t.narrow(0, 0, k);
      if (k < 3) prompts = torch::Tensor();  // too few points: fall back to the source depth
    }
    const MethodOutput o = method->predict(src, tgt.camera, static_cast<uint64_t>(i), prompts);
    PairResult r;
    r.index = i;
    r.bin = p.bin;
    r.baseline = p.baseline;
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
    out << result_json(r).dump() << "\n" << std::flush;  // appended as it finishes: a crash loses one pair
    results.push_back(r);
    if (examples < config_.scoring.examples) {
      std::vector<cv::Mat> cols = {tensor_to_image(src.image), tensor_to_image(tgt.image), tensor_to_image(o.image),
                                   tensor_to_image(mask.unsqueeze(0).expand({3, -1, -1}).contiguous())};
      cv::Mat panel;
      cv::hconcat(cols, panel);
      write_image((dir / "examples" / cat(safe(mo.name), "_pair", i, ".png")).string(), panel);
      ++examples;
    }
    bar.postfix(cat("PSNR ", std::setprecision(3), r.psnr));
    bar.tick();
  }
  bar.finish();
  std::sort(results.begin(), results.end(), [](const PairResult& a, const PairResult& b) { return a.index < b.index; });
  return results;
}

std::vector<ReportRow> Evaluator::run(bool pairs_only) {
  fs::create_directories(config_.scoring.out);
  write_file_atomic((fs::path(config_.scoring.out) / "config.json").string(), config_to_json(config_).dump(2) + "\n");
  const std::vector<std::string>& nets = config_.scoring.lpips;
  std::vector<ReportRow> rows;
  std::vector<std::string> notes = notes_;
  if (config_.scoring.max_per_bin > 0)
    notes.push_back(cat("only the first ", config_.scoring.max_per_bin,
                        " pairs of each bin were scored "
                        "(scoring.max_per_bin); the full protocol scores every pair of the manifest"));
  for (size_t d = 0; d < config_.datasets.size(); ++d) {
    const auto sequences = load_eval_dataset(config_.datasets[d]);
    const Manifest m = manifest(d, sequences);
    std::vector<std::string> labels;
    for (size_t b = 0; b < m.bin_counts.size(); ++b) {
      labels.push_back(m.bin_label(static_cast<int>(b)));
      if (m.bin_counts[b] < config_.protocol.pairs_per_bin)
        notes.push_back(cat(config_.datasets[d].name, ": bin ", labels.back(), " has ", m.bin_counts[b], " of ",
                            config_.protocol.pairs_per_bin, " pairs (", m.bin_candidates[b],
                            " candidates passed the filters); it is not padded"));
    }
    if (pairs_only) continue;
    std::vector<int64_t> requested(m.bin_counts.size(), config_.protocol.pairs_per_bin);
    const auto& ds = config_.datasets[d];
    const std::vector<ColmapModel> points =
        ds.prompts == "points3d" ? load_eval_points3d(ds) : std::vector<ColmapModel>{};
    for (const auto& mo : config_.methods) {
      const auto results = score(d, sequences, m, mo, points);
      auto r = summarize(config_.datasets[d].name, mo.name, labels, requested, results, nets);
      rows.insert(rows.end(), r.begin(), r.end());
    }
  }
  if (!pairs_only) {
    write_reports(config_.scoring.out, rows, nets, notes);
    log_info("eval: reports in ", config_.scoring.out, " (report.md, report.csv, report.json, speed_quality.png)");
  }
  return rows;
}

}  // namespace isplat
