// AbsRel / delta1 scoring of depth priors on evaluation datasets, with Markdown/CSV/JSON reports.
#include "eval/depth_eval.h"

#include <torch/torch.h>

#include <filesystem>

#include "core/config.h"
#include "core/error.h"
#include "core/log.h"
#include "core/progress.h"
#include "data/tuples.h"
#include "io/atomic_file.h"
#include "io/csv.h"

namespace isplat {
namespace fs = std::filesystem;

void NamedPrior::visit(ConfigVisitor& v) {
  v.field("name", name, "name in the report (e.g. unet-rooms, squeeze-mixed)");
  v.section("prior", "the depth prior (model.prior keys)", prior);
}

void DepthEvalConfig::visit(ConfigVisitor& v) {
  v.section("runtime", "threads, seed and logging", runtime);
  v.list("datasets", "datasets with reference depth", datasets);
  v.list("priors", "depth priors to score", priors);
  v.field("frames", frames, "frames scored per dataset, evenly spaced over its frames with depth", Range::at_least(1));
  v.field("range_edges", range_edges, "depth range lower edges in metres; the last range is open", Range::at_least(0));
  v.field("out", out, "report folder");
}

namespace {
torch::Tensor scored_pixels(const torch::Tensor& pred, const torch::Tensor& depth, const torch::Tensor& valid,
                            double lo, double hi) {
  return (valid > 0) & (depth > 0) & (pred > 0) & torch::isfinite(pred) & (depth >= lo) & (depth < hi);
}
}  // namespace

ScaleSummary summarize_scales(const std::vector<double>& frame_scales) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (frame_scales.empty()) return {nan, nan};
  double sum = 0, sum_sq = 0;
  for (double s : frame_scales) sum += std::log(s), sum_sq += std::log(s) * std::log(s);
  const double n = static_cast<double>(frame_scales.size()), mean = sum / n;
  return {std::exp(mean), std::exp(std::sqrt(std::max(0.0, sum_sq / n - mean * mean)))};
}

DepthScale depth_scale(const torch::Tensor& pred, const torch::Tensor& depth, const torch::Tensor& valid) {
  const auto m = scored_pixels(pred, depth, valid, 0, std::numeric_limits<double>::infinity());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (m.sum().item<int64_t>() == 0) return {nan, nan};
  const auto p = pred.masked_select(m).to(torch::kFloat64), d = depth.masked_select(m).to(torch::kFloat64);
  const double ratio = (p / d).median().item<double>();
  return {ratio, ((p / ratio - d).abs() / d).mean().item<double>()};
}

DepthErrors depth_errors(const torch::Tensor& pred, const torch::Tensor& depth, const torch::Tensor& valid, double lo,
                         double hi) {
  auto m = scored_pixels(pred, depth, valid, lo, hi);
  DepthErrors e;
  e.pixels = m.sum().item<int64_t>();
  if (e.pixels == 0) return e;
  const auto p = pred.masked_select(m).to(torch::kFloat64), d = depth.masked_select(m).to(torch::kFloat64);
  e.abs_rel_sum = ((p - d).abs() / d).sum().item<double>();
  e.delta1_count = (torch::max(p / d, d / p) < 1.25).sum().item<double>();
  return e;
}

std::vector<DepthScore> evaluate_depth_priors(const DepthEvalConfig& c) {
  ISPLAT_CHECK(!c.datasets.empty(), "depth evaluation: no datasets (config key datasets)");
  ISPLAT_CHECK(!c.priors.empty(), "depth evaluation: no priors (config key priors)");
  const auto& edges = c.range_edges;
  ISPLAT_CHECK(!edges.empty() && std::is_sorted(edges.begin(), edges.end()), "range_edges must increase");
  auto label = [&](size_t r) {
    return r + 1 < edges.size() ? cat("[", edges[r], ",", edges[r + 1], ") m") : cat("[", edges[r], ",inf) m");
  };
  std::vector<DepthScore> scores;
  for (const auto& np : c.priors) {
    auto prior = make_depth_prior(np.prior);
    for (const auto& ds : c.datasets) {
      const auto seqs = load_eval_dataset(ds);
      std::vector<std::pair<size_t, size_t>> frames;
      for (size_t s = 0; s < seqs.size(); ++s)
        for (size_t f = 0; f < seqs[s].frames.size(); ++f)
          if (seqs[s].frames[f].depth != DepthSource::None) frames.emplace_back(s, f);
      ISPLAT_CHECK(!frames.empty(), "depth evaluation: dataset '", ds.name, "' has no frame with depth");
      const size_t n = std::min<size_t>(frames.size(), static_cast<size_t>(c.frames));
      std::vector<DepthErrors> ranges(edges.size());
      double abs_rel = 0, delta1 = 0, abs_rel_aligned = 0, coverage = 0;
      std::vector<double> frame_scales;
      int64_t counted = 0, pixels = 0, floor_scaled = 0;
      ProgressBar bar(cat("depth ", np.name, "/", ds.name), static_cast<int64_t>(n), "frame");
      for (size_t k = 0; k < n; ++k, bar.tick()) {
        const auto [s, f] = frames[k * frames.size() / n];
        const LoadedFrame lf = load_frame(seqs[s], f);
        const ViewTensors v = make_view_tensors(lf, seqs[s].frames[f].name, ds.width ? ds.width : lf.image.cols,
                                                ds.height ? ds.height : lf.image.rows);
        PriorInput in;
        in.image = v.image;
        in.K = v.camera.K;
        in.depth = v.depth;  // only the dataset and sparse priors read it
        in.valid = v.valid;
        in.seed = k;
        const PriorOutput out = prior->predict(in);
        floor_scaled += out.floor_scaled;
        const DepthErrors all = depth_errors(out.depth, v.depth, v.valid * out.valid);
        if (all.pixels > 0) {
          abs_rel += all.abs_rel_sum / all.pixels, delta1 += all.delta1_count / all.pixels, ++counted;
          pixels += all.pixels;
          const DepthScale sc = depth_scale(out.depth, v.depth, v.valid * out.valid);
          frame_scales.push_back(sc.median_ratio), abs_rel_aligned += sc.abs_rel_aligned;
          coverage += static_cast<double>(all.pixels) / std::max<int64_t>(1, (v.valid > 0).sum().item<int64_t>());
        }
        for (size_t r = 0; r < edges.size(); ++r) {
          const double hi = r + 1 < edges.size() ? edges[r + 1] : std::numeric_limits<double>::infinity();
          const DepthErrors e = depth_errors(out.depth, v.depth, v.valid * out.valid, edges[r], hi);
          ranges[r].abs_rel_sum += e.abs_rel_sum, ranges[r].delta1_count += e.delta1_count;
          ranges[r].pixels += e.pixels;
        }
      }
      bar.finish();
      const double nan = std::numeric_limits<double>::quiet_NaN();
      const ScaleSummary scale = summarize_scales(frame_scales);
      scores.push_back(
          {ds.name, np.name, "all", counted, pixels, counted ? abs_rel / counted : nan,
           counted ? delta1 / counted : nan, scale.mean, scale.spread, counted ? abs_rel_aligned / counted : nan,
           counted ? coverage / counted : nan,
           np.prior.camera_height_m > 0 ? static_cast<double>(floor_scaled) / static_cast<double>(n) : nan});
      for (size_t r = 0; r < edges.size(); ++r) {
        const auto& e = ranges[r];
        scores.push_back({ds.name, np.name, label(r), counted, e.pixels, e.pixels ? e.abs_rel_sum / e.pixels : nan,
                          e.pixels ? e.delta1_count / e.pixels : nan, nan, nan, nan, nan, nan});
      }
    }
  }
  // Reports: one table per dataset, priors as rows, ranges as column groups.
  fs::create_directories(c.out);
  auto fmt = [](double v, int d) {
    if (!std::isfinite(v)) return std::string("n/a");
    std::ostringstream os;
    os << std::fixed << std::setprecision(d) << v;
    return os.str();
  };
  std::ostringstream md;
  md << "# Depth prior evaluation\n\nAbsRel (lower is better) and δ<1.25 (higher is better) against the datasets' "
        "depth at evaluation size. \"all\": means over frames; depth ranges: pooled over the pixels in the range. "
        "Scale apart from shape: \"scale\" is the geometric mean over frames of each frame's median "
        "prediction / reference (1 = right metric scale), \"spread\" how far a typical frame's scale strays from that "
        "mean (exp of the standard deviation of the log scales; 1 = every frame alike), \"AbsRel aligned\" the AbsRel "
        "after dividing each frame "
        "by that median (shape error only). \"coverage\": the share of the reference's valid pixels the prior also "
        "marks valid (a prior that cuts far depth as sky is scored only where it keeps depth). \"floor\": the share of "
        "frames whose metric scale came from the camera height (prior.camera_height_m; n/a when off).\n\n";
  CsvTable csv;
  csv.header = {"dataset", "prior", "range",        "frames",          "pixels",   "abs_rel",
                "delta1",  "scale", "scale_spread", "abs_rel_aligned", "coverage", "floor"};
  nlohmann::ordered_json js = nlohmann::ordered_json::array();
  for (const auto& ds : c.datasets) {
    md << "## " << ds.name
       << "\n\n| prior | all AbsRel | all δ1 | scale | spread | AbsRel aligned | coverage | floor |";
    for (size_t r = 0; r < edges.size(); ++r) md << " " << label(r) << " AbsRel / δ1 (px) |";
    md << "\n|---|---|---|---|---|---|---|---|";
    for (size_t r = 0; r < edges.size(); ++r) md << "---|";
    md << "\n";
    for (const auto& np : c.priors) {
      md << "| " << np.name;
      for (const auto& s : scores) {
        if (s.dataset != ds.name || s.prior != np.name) continue;
        if (s.range == "all")
          md << " | " << fmt(s.abs_rel, 3) << " | " << fmt(s.delta1, 3) << " | " << fmt(s.scale, 3) << " | "
             << fmt(s.scale_spread, 3) << " | " << fmt(s.abs_rel_aligned, 3) << " | " << fmt(s.coverage, 3) << " | "
             << fmt(s.floor, 2);
        else
          md << " | " << fmt(s.abs_rel, 3) << " / " << fmt(s.delta1, 3) << " (" << s.pixels << ")";
      }
      md << " |\n";
    }
    md << "\n";
  }
  for (const auto& s : scores) {
    csv.rows.push_back({s.dataset, s.prior, s.range, std::to_string(s.frames), std::to_string(s.pixels),
                        fmt(s.abs_rel, 5), fmt(s.delta1, 5), fmt(s.scale, 5), fmt(s.scale_spread, 5),
                        fmt(s.abs_rel_aligned, 5), fmt(s.coverage, 5), fmt(s.floor, 5)});
    auto num = [](double v) { return std::isfinite(v) ? nlohmann::ordered_json(v) : nlohmann::ordered_json(nullptr); };
    js.push_back({{"dataset", s.dataset},
                  {"prior", s.prior},
                  {"range", s.range},
                  {"frames", s.frames},
                  {"pixels", s.pixels},
                  {"abs_rel", num(s.abs_rel)},
                  {"delta1", num(s.delta1)},
                  {"scale", num(s.scale)},
                  {"scale_spread", num(s.scale_spread)},
                  {"abs_rel_aligned", num(s.abs_rel_aligned)},
                  {"coverage", num(s.coverage)},
                  {"floor", num(s.floor)}});
  }
  write_file_atomic((fs::path(c.out) / "report.md").string(), md.str());
  write_csv((fs::path(c.out) / "report.csv").string(), csv);
  write_file_atomic((fs::path(c.out) / "report.json").string(), js.dump(2) + "\n");
  log_info("depth evaluation: report in ", c.out);
  return scores;
}

}  // namespace isplat
