// The stamp beside each method's results: the options and fingerprints they were scored with, checked on every run.
#include "eval/method_stamp.h"

#include <filesystem>

#include "core/config.h"
#include "core/error.h"
#include "eval/datasets.h"
#include "eval/methods.h"
#include "io/atomic_file.h"

namespace isplat {

namespace fs = std::filesystem;

namespace {

// Adds to a stamp the options it predates: each key it lacks where the config now holds that option's default
// (results scored before an option existed were scored as its default). True when it added any.
bool adopt_new_defaults(nlohmann::json& before, const nlohmann::json& now, const nlohmann::json& defaults) {
  if (!before.is_object() || !now.is_object() || !defaults.is_object()) return false;
  bool added = false;
  for (const auto& [key, value] : now.items()) {
    if (!defaults.contains(key)) continue;
    if (!before.contains(key)) {
      if (value != defaults[key]) continue;
      before[key] = value;
      added = true;
    } else {
      added = adopt_new_defaults(before[key], value, defaults[key]) || added;
    }
  }
  return added;
}

// A method's options and the scoring options that change its results: what a stamp records.
nlohmann::json stamp_options(const MethodOptions& mo, const ScoringOptions& scoring) {
  nlohmann::json j = nlohmann::json::parse(config_to_json(mo).dump());
  j.erase("name");
  j.erase("sweep");  // the point is the results file's and each record's; its options are stamped above
  j.erase("precision");
  if (mo.type == "model") j["precision"] = precision_name(method_precision(mo));  // as run, whichever key chose it
  j["scoring.crack_edge_margin"] = scoring.crack_edge_margin;
  j["scoring.crack_holes"] = scoring.crack_holes;
  j["scoring.crack_side"] = scoring.crack_side;
  j["scoring.crack_min_error"] = scoring.crack_min_error;
  j["scoring.crack_edge_side"] = scoring.crack_edge_side;
  j["scoring.crack_depth"] = scoring.crack_depth;
  j["scoring.display_factors"] = scoring.display_factors;
  j["scoring.align_scale"] = scoring.align_scale;
  j["scoring.regions"] = scoring.regions;
  return j;
}

}  // namespace

// Results are found by method name, so a method whose options or weights changed must not resume from them:
// the options and the checkpoint's content fingerprint are stamped beside the results (<results>.method.json)
// and compared on every run. A log without a stamp (older runs) adopts the current options; a stamp without
// a fingerprint (older runs) adopts the current checkpoint's; a stamp older than an option adopts its default.
void check_method_stamp(const std::string& results, const MethodOptions& mo, const ScoringOptions& scoring,
                        const nlohmann::json& dataset) {
  if (!mo.checkpoint.empty()) require_finished_run(mo.name, mo.checkpoint);  // before anything is stamped
  nlohmann::json now = stamp_options(mo, scoring);
  if (!mo.checkpoint.empty() && fs::exists(mo.checkpoint))
    now["checkpoint_fingerprint"] = file_fingerprint(mo.checkpoint);
  if (!dataset.is_null()) now["dataset_fingerprint"] = dataset;
  const std::string stamp = results + ".method.json";
  // A stamp over no scored pair (a run that stopped before its first, e.g. on a refused option) guards nothing.
  const bool scored = fs::exists(results) && fs::file_size(results) > 0;
  if (scored && fs::exists(stamp)) {
    nlohmann::json before = read_json_file(stamp);  // names the file when it is unreadable
    // The data the results were scored on (a stamp written before fingerprints adopts the current one).
    bool adopt_data = false;
    if (before.is_object() && !now.contains("dataset_fingerprint")) before.erase("dataset_fingerprint");
    if (before.is_object() && now.contains("dataset_fingerprint")) {
      if (!before.contains("dataset_fingerprint")) {
        before["dataset_fingerprint"] = now["dataset_fingerprint"];
        adopt_data = true;
      } else if (const std::string changes =
                     fingerprint_changes(before["dataset_fingerprint"], now["dataset_fingerprint"]);
                 !changes.empty()) {
        fail("eval: ", results, " was scored on other data for method '", mo.name, "': ", changes, " (", stamp,
             "); choose another scoring.out or delete both files to score it again");
      }
    }
    const bool adopt_weights =
        before.is_object() && !before.contains("checkpoint_fingerprint") && now.contains("checkpoint_fingerprint");
    if (adopt_weights) before["checkpoint_fingerprint"] = now["checkpoint_fingerprint"];
    bool adopt = adopt_data || adopt_weights;
    nlohmann::json defaults = stamp_options(MethodOptions{}, ScoringOptions{});
    defaults["precision"] = "fp32";  // what everything scored before runtime.precision existed ran in
    adopt = adopt_new_defaults(before, now, defaults) || adopt;
    if (before.is_object() && now.contains("checkpoint_fingerprint") &&
        before.value("checkpoint_fingerprint", "") != now["checkpoint_fingerprint"].get<std::string>() &&
        before.value("checkpoint", "") == mo.checkpoint)
      fail("eval: ", results, " was scored with other weights for method '", mo.name, "': ", mo.checkpoint,
           " changed since (", stamp, " has fingerprint ", before.value("checkpoint_fingerprint", ""),
           ", the file now ", now["checkpoint_fingerprint"].get<std::string>(),
           "); rename the method or delete both files to score it again");
    ISPLAT_CHECK(before == now, "eval: ", results, " was scored with other options for method '", mo.name, "' (", stamp,
                 " has ", before.dump(), ", the config now gives ", now.dump(),
                 "); rename the method or delete both files to score it again");
    if (!adopt) return;
  }
  fs::create_directories(fs::path(stamp).parent_path());
  write_file_atomic(stamp, now.dump(2) + "\n");
}

}  // namespace isplat
