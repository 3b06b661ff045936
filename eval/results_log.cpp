// PairResult <-> JSON and the append-only results log.
#include "eval/results_log.h"

#include <cmath>
#include <limits>
#include <tuple>

#include "core/error.h"
#include "core/log.h"

namespace isplat {

nlohmann::json result_json(const PairResult& r) {
  auto num = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  nlohmann::json j = {{"index", r.index},
                      {"bin", r.bin},
                      {"baseline", r.baseline},
                      {"psnr", num(r.psnr)},
                      {"ssim", r.ssim},
                      {"infer_ms", r.infer_ms},
                      {"render_ms", r.render_ms},
                      {"gaussians", r.gaussians},
                      {"decoded", r.decoded},
                      {"mask_fraction", r.mask_fraction},
                      {"peak_mb", num(r.peak_mb)},
                      {"work_mb", num(r.work_mb)},
                      {"hole_rate", num(r.hole_rate)},
                      {"crack_rate", num(r.crack_rate)},
                      {"normal_deg", num(r.normal_deg)},
                      {"rotation_deg", num(r.rotation_deg)}};
  if (!r.motion.empty()) j["motion"] = r.motion;
  for (const DisplayScore& d : r.display)
    j["display"].push_back({{"factor", d.factor}, {"psnr", num(d.psnr)}, {"hole_rate", num(d.hole_rate)}});
  // Written only when measured, so records of runs without them are as before.
  auto region = [&](const RegionScore& g) {
    return nlohmann::json{{"share", num(g.share)},
                          {"psnr", num(g.psnr)},
                          {"lpips", num(g.lpips)},
                          {"detail", num(g.detail)},
                          {"density", num(g.density)}};
  };
  for (const auto& [name, g] : r.regions) j["regions"][name] = region(g);
  if (std::isfinite(r.source_view.share)) j["source_view"] = region(r.source_view);
  if (std::isfinite(r.scale)) j["scale"] = r.scale, j["scale_samples"] = r.scale_samples;
  for (const auto& [key, d] : {std::pair{"unprompted", &r.unprompted}, {"removed", &r.removed}})
    if (d->pixels > 0)
      j[std::string("densify_") + key] = {
          {"abs_rel", num(d->abs_rel)}, {"delta1", num(d->delta1)}, {"pixels", d->pixels}};
  for (const auto& [k, v] : r.lpips) j["lpips_" + k] = num(v);
  if (!r.stage_ms.empty()) j["stage_ms"] = r.stage_ms;
  if (!r.prune_counts.empty()) j["prune"] = r.prune_counts;
  if (!r.method.name.empty()) j["method"] = r.method.name;
  if (!r.method.sweep.key.empty()) j["sweep_key"] = r.method.sweep.key;
  if (!r.method.sweep.budget.empty()) j["budget"] = r.method.sweep.budget;
  if (r.method.sweep.any()) j["sweep_value"] = r.method.sweep.value;
  return j;
}

namespace {
// Values a real evaluation can produce; anything else is a damaged or edited line (PSNR 1e308 would
// dominate every average of the report).
void check_range(const char* key, double v, double lo, double hi) {
  ISPLAT_CHECK(std::isfinite(v) && v >= lo && v <= hi, "'", key, "' = ", v, " is outside [", lo, ", ", hi, "]");
}
}  // namespace

static RegionScore region_from_json(const nlohmann::json& o, const std::string& key) {
  RegionScore g;
  for (const auto& [field, value, hi] : {std::tuple{"share", &g.share, 1.0},
                                         {"psnr", &g.psnr, 1000.0},
                                         {"lpips", &g.lpips, 100.0},
                                         {"detail", &g.detail, 1e9},
                                         {"density", &g.density, 1e9}}) {
    const nlohmann::json& v = o.at(field);
    if (!v.is_null()) *value = v.get<double>(), check_range((key + "." + field).c_str(), *value, 0, hi);
  }
  return g;
}

PairResult result_from_json(const nlohmann::json& j) {
  PairResult r;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  r.index = j.at("index").get<int64_t>();
  ISPLAT_CHECK(r.index >= 0, "negative pair index ", r.index);
  const int64_t bin = j.at("bin").get<int64_t>();
  ISPLAT_CHECK(bin >= 0 && bin < 1000, "'bin' = ", bin, " is not a bin index");
  r.bin = static_cast<int>(bin);
  r.baseline = j.at("baseline").get<double>();
  check_range("baseline", r.baseline, 0, 1e6);
  // PSNR of identical images is +inf, which JSON cannot hold: it is written as null.
  r.psnr = j.at("psnr").is_null() ? std::numeric_limits<double>::infinity() : j.at("psnr").get<double>();
  if (!j.at("psnr").is_null()) check_range("psnr", r.psnr, 0, 1000);
  r.ssim = j.at("ssim").get<double>();
  check_range("ssim", r.ssim, -1, 1);
  r.infer_ms = j.at("infer_ms").get<double>();
  r.render_ms = j.at("render_ms").get<double>();
  check_range("infer_ms", r.infer_ms, 0, 1e9);
  check_range("render_ms", r.render_ms, 0, 1e9);
  r.gaussians = j.at("gaussians").get<int64_t>();
  ISPLAT_CHECK(r.gaussians >= 0, "'gaussians' = ", r.gaussians, " is negative");
  r.mask_fraction = j.at("mask_fraction").get<double>();
  check_range("mask_fraction", r.mask_fraction, 0, 1);
  // Added later: optional, so older logs still resume.
  r.decoded = j.contains("decoded") ? j.at("decoded").get<int64_t>() : r.gaussians;
  ISPLAT_CHECK(r.decoded >= 0, "'decoded' = ", r.decoded, " is negative");
  r.peak_mb = j.contains("peak_mb") && !j.at("peak_mb").is_null() ? j.at("peak_mb").get<double>() : nan;
  if (std::isfinite(r.peak_mb)) check_range("peak_mb", r.peak_mb, 0, 1e8);
  auto optional = [&](const char* key, double& v, double hi) {
    if (!j.contains(key) || j.at(key).is_null()) return;
    v = j.at(key).get<double>();
    check_range(key, v, 0, hi);
  };
  optional("work_mb", r.work_mb, 1e8);
  optional("hole_rate", r.hole_rate, 1);
  optional("crack_rate", r.crack_rate, 1);
  optional("normal_deg", r.normal_deg, 180);
  optional("rotation_deg", r.rotation_deg, 180);
  if (j.contains("motion")) {
    r.motion = j.at("motion").get<std::string>();
    ISPLAT_CHECK(r.motion == "lateral" || r.motion == "forward" || r.motion == "rotation", "'motion' = '", r.motion,
                 "' is not lateral, forward or rotation");
  }
  if (j.contains("display"))
    for (const auto& d : j.at("display")) {
      DisplayScore s;
      s.factor = d.at("factor").get<double>();
      check_range("display.factor", s.factor, 1, 8);
      if (!d.at("psnr").is_null()) s.psnr = d.at("psnr").get<double>(), check_range("display.psnr", s.psnr, 0, 1000);
      if (!d.at("hole_rate").is_null())
        s.hole_rate = d.at("hole_rate").get<double>(), check_range("display.hole_rate", s.hole_rate, 0, 1);
      r.display.push_back(s);
    }
  if (j.contains("regions"))
    for (auto it = j.at("regions").begin(); it != j.at("regions").end(); ++it)
      r.regions[it.key()] = region_from_json(it.value(), "regions." + it.key());
  if (j.contains("source_view")) r.source_view = region_from_json(j.at("source_view"), "source_view");
  if (j.contains("scale")) {
    r.scale = j.at("scale").get<double>();
    check_range("scale", r.scale, 1e-12, 1e12);
    r.scale_samples = j.value("scale_samples", int64_t{0});
    ISPLAT_CHECK(r.scale_samples >= 0, "'scale_samples' = ", r.scale_samples, " is negative");
  }
  for (const auto& [key, d] : {std::pair{"densify_unprompted", &r.unprompted}, {"densify_removed", &r.removed}})
    if (j.contains(key)) {
      const auto& o = j.at(key);
      d->pixels = o.at("pixels").get<int64_t>();
      ISPLAT_CHECK(d->pixels >= 0, "'", key, ".pixels' = ", d->pixels, " is negative");
      if (!o.at("abs_rel").is_null()) d->abs_rel = o.at("abs_rel").get<double>(), check_range(key, d->abs_rel, 0, 1e6);
      if (!o.at("delta1").is_null()) d->delta1 = o.at("delta1").get<double>(), check_range(key, d->delta1, 0, 1);
    }
  if (j.contains("stage_ms"))
    for (auto it = j.at("stage_ms").begin(); it != j.at("stage_ms").end(); ++it) {
      r.stage_ms[it.key()] = it.value().get<double>();
      check_range(it.key().c_str(), r.stage_ms[it.key()], 0, 1e9);
    }
  if (j.contains("prune"))
    for (auto it = j.at("prune").begin(); it != j.at("prune").end(); ++it) {
      const int64_t count = it.value().get<int64_t>();
      ISPLAT_CHECK(count >= 0, "'prune.", it.key(), "' = ", count, " is negative");
      r.prune_counts[it.key()] = count;
    }
  r.method.name = j.value("method", "");
  r.method.sweep.key = j.value("sweep_key", "");
  r.method.sweep.budget = j.value("budget", "");
  if (r.method.sweep.any()) r.method.sweep.value = j.at("sweep_value").get<double>();
  ISPLAT_CHECK(r.method.sweep.key.empty() || r.method.sweep.budget.empty(),
               "a record with both a sweep_key and a budget");
  for (auto it = j.begin(); it != j.end(); ++it)
    if (it.key().rfind("lpips_", 0) == 0) {
      r.lpips[it.key().substr(6)] = it.value().is_null() ? nan : it.value().get<double>();
      if (!it.value().is_null()) check_range(it.key().c_str(), r.lpips[it.key().substr(6)], 0, 10);
    }
  return r;
}

ResultsLog::ResultsLog(const std::string& path, const std::function<std::string(const PairResult&)>& check,
                       const MethodId& method)
    : method_(method) {
  for (const auto& j : read_jsonl(path, [&](int64_t line, const std::string&why) {
         log_warn("eval: ", path, ":", line, " is unreadable (", why, "); that pair is scored again");
       })) {
    try {
      PairResult r = result_from_json(j);
      if (!method_.name.empty() && r.method.name.empty()) r.method = method_;  // a record from before the fields
      if (!method_.name.empty() && !(r.method == method_))
        fail("a record of method '", r.method.label(), "' in the log of '", method_.label(), "'");
      const std::string why = check ? check(r) : "";
      if (!why.empty()) fail(why);
      done_.emplace(r.index, r);
    } catch (const std::exception& e) {
      log_warn("eval: ", path, ": a record is unusable (", e.what(), "); that pair is scored again");
    }
  }
  writer_ = std::make_unique<JsonlWriter>(path);
}

void ResultsLog::append(const PairResult& r) {
  PairResult stamped = r;
  if (!method_.name.empty()) stamped.method = method_;
  writer_->write(result_json(stamped));
  done_.emplace(r.index, stamped);
}

std::string check_against_manifest(const PairResult& r, const Manifest& m) {
  if (r.index < 0 || r.index >= static_cast<int64_t>(m.pairs.size()))
    return cat("pair ", r.index, " is not in the manifest (", m.pairs.size(), " pairs)");
  const Pair& p = m.pairs[static_cast<size_t>(r.index)];
  if (r.bin != p.bin) return cat("pair ", r.index, " has bin ", r.bin, "; the manifest says ", p.bin);
  if (std::fabs(r.baseline - p.baseline) > 1e-6 * std::max(1.0, std::fabs(p.baseline)))
    return cat("pair ", r.index, " has baseline ", r.baseline, "; the manifest says ", p.baseline);
  return "";
}

}  // namespace isplat
