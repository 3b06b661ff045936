// The per-pair results of one method on one dataset, as a JSON-lines log that an interrupted evaluation
// resumes from (and that shards of one evaluation are merged from).
#pragma once
#include <map>
#include <memory>
#include <string>

#include "eval/report.h"
#include "io/jsonl.h"

namespace isplat {

// One pair's record as a JSON object, and back (non-finite values are null; a PSNR of null reads as +inf).
nlohmann::json result_json(const PairResult& r);
PairResult result_from_json(const nlohmann::json& j);

class ResultsLog {
 public:
  // Reads the finished pairs of `path` (a missing file is an empty log); unreadable lines are warned about
  // and their pairs scored again.
  explicit ResultsLog(const std::string& path);
  const std::map<int64_t, PairResult>& done() const { return done_; }
  void append(const PairResult& r);  // flushed before it returns: a crash loses at most one pair

 private:
  std::map<int64_t, PairResult> done_;
  std::unique_ptr<JsonlWriter> writer_;
};

}  // namespace isplat
