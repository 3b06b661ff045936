// The per-pair results of one method on one dataset, as a JSON-lines log that an interrupted evaluation
// resumes from (and that shards of one evaluation are merged from).
#pragma once
#include <functional>
#include <map>
#include <memory>
#include <string>

#include "eval/pairs.h"
#include "eval/report.h"
#include "io/jsonl.h"

namespace isplat {

// One pair's record as a JSON object, and back (non-finite values are null; a PSNR of null reads as +inf).
nlohmann::json result_json(const PairResult& r);
PairResult result_from_json(const nlohmann::json& j);

class ResultsLog {
 public:
  // Reads the finished pairs of `path` (a missing file is an empty log). Unreadable lines, values out of
  // range and records that `check` (optional) returns a reason for, e.g. a bin that disagrees with the
  // manifest, are warned about and their pairs scored again.
  explicit ResultsLog(const std::string& path, const std::function<std::string(const PairResult&)>& check = nullptr);
  const std::map<int64_t, PairResult>& done() const { return done_; }
  void append(const PairResult& r);  // flushed before it returns: a crash loses at most one pair

 private:
  std::map<int64_t, PairResult> done_;
  std::unique_ptr<JsonlWriter> writer_;
};

// Why `r` cannot be a result of manifest `m` ("" when it can): a pair index, bin or baseline that the
// manifest does not have. The check a ResultsLog is opened with.
std::string check_against_manifest(const PairResult& r, const Manifest& m);

}  // namespace isplat
