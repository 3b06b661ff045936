// JSON-lines logs (one object per line): the trainer's log and the evaluator's per-pair results.
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace isplat {

// Appends records to `path`, flushing and checking each one, so a crash loses at most the record being
// written and a full disk is an Error naming the file. A half-written last line left by a killed writer
// is terminated first, so it never merges with the next record. A symlink at `path` is refused.
class JsonlWriter {
 public:
  explicit JsonlWriter(std::string path);
  void write(const nlohmann::json& record);
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

// Every parsable line of `path` (none when the file is missing). A line that does not parse is passed to
// `on_bad(line_number, reason)` and skipped.
std::vector<nlohmann::json> read_jsonl(const std::string& path,
                                       const std::function<void(int64_t, const std::string&)>& on_bad = nullptr);

}  // namespace isplat
