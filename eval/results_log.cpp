// PairResult <-> JSON and the append-only results log.
#include "eval/results_log.h"

#include <cmath>
#include <limits>

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
                      {"mask_fraction", r.mask_fraction}};
  for (const auto& [k, v] : r.lpips) j["lpips_" + k] = num(v);
  return j;
}

PairResult result_from_json(const nlohmann::json& j) {
  PairResult r;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  r.index = j.at("index").get<int64_t>();
  r.bin = j.at("bin").get<int>();
  r.baseline = j.at("baseline").get<double>();
  // PSNR of identical images is +inf, which JSON cannot hold: it is written as null.
  r.psnr = j.at("psnr").is_null() ? std::numeric_limits<double>::infinity() : j.at("psnr").get<double>();
  r.ssim = j.at("ssim").get<double>();
  r.infer_ms = j.at("infer_ms").get<double>();
  r.render_ms = j.at("render_ms").get<double>();
  r.gaussians = j.at("gaussians").get<int64_t>();
  r.mask_fraction = j.at("mask_fraction").get<double>();
  for (auto it = j.begin(); it != j.end(); ++it)
    if (it.key().rfind("lpips_", 0) == 0)
      r.lpips[it.key().substr(6)] = it.value().is_null() ? nan : it.value().get<double>();
  ISPLAT_CHECK(r.index >= 0, "negative pair index ", r.index);
  return r;
}

ResultsLog::ResultsLog(const std::string& path) {
  for (const auto& j : read_jsonl(path, [&](int64_t line, const std::string&why) {
         log_warn("eval: ", path, ":", line, " is unreadable (", why, "); that pair is scored again");
       })) {
    try {
      PairResult r = result_from_json(j);
      done_.emplace(r.index, r);
    } catch (const std::exception& e) {
      log_warn("eval: ", path, ": a record is unusable (", e.what(), "); that pair is scored again");
    }
  }
  writer_ = std::make_unique<JsonlWriter>(path);
}

void ResultsLog::append(const PairResult& r) {
  writer_->write(result_json(r));
  done_.emplace(r.index, r);
}

}  // namespace isplat
