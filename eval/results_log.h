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

// One pair's record as a JSON object, and back (non-finite values are null; a PSNR of null reads as +inf). The
// method that scored it is in the fields method, sweep_key, budget and sweep_value (when known).
nlohmann::json result_json(const PairResult& r);
PairResult result_from_json(const nlohmann::json& j);

class ResultsLog {
 public:
  // Reads the finished pairs of `path` (a missing file is an empty log). Unreadable lines, values out of
  // range and records that `check` (optional) returns a reason for, e.g. a bin that disagrees with the
  // manifest, are warned about and their pairs scored again. With `method` (a name), records of another method
  // or sweep point are too; records without method fields (logs written before them, whose file name was made
  // from the same fields) are the file's method, and appended records carry its fields.
  explicit ResultsLog(const std::string& path, const std::function<std::string(const PairResult&)>& check = nullptr,
                      const MethodId& method = {});
  const std::map<int64_t, PairResult>& done() const { return done_; }
  void append(const PairResult& r);  // flushed before it returns: a crash loses at most one pair

 private:
  std::map<int64_t, PairResult> done_;
  MethodId method_;
  std::unique_ptr<JsonlWriter> writer_;
};

// Why `r` cannot be a result of manifest `m` ("" when it can): a pair index, bin or baseline that the
// manifest does not have. The check a ResultsLog is opened with.
std::string check_against_manifest(const PairResult& r, const Manifest& m);

}  // namespace isplat
