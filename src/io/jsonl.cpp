// JSON-lines append and read with per-record flush checks and tolerant reading.
#include "io/jsonl.h"

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "core/error.h"

namespace isplat {
namespace fs = std::filesystem;

JsonlWriter::JsonlWriter(std::string path) : path_(std::move(path)) {
  std::error_code ec;
  if (!fs::exists(path_, ec) || fs::file_size(path_, ec) == 0) return;
  std::ifstream in(path_, std::ios::binary);
  in.seekg(-1, std::ios::end);
  char last = '\n';
  in.get(last);
  if (last != '\n') {  // a record cut short by a kill: end it so the next record starts on its own line
    std::ofstream out(path_, std::ios::app | std::ios::binary);
    out << '\n';
    ISPLAT_CHECK(out.flush(), path_, ": cannot append (disk full or read-only?)");
  }
}

void JsonlWriter::write(const nlohmann::json& record) {
  std::ofstream out(path_, std::ios::app | std::ios::binary);
  ISPLAT_CHECK(out.is_open(), path_, ": cannot open for appending");
  out << record.dump() << '\n';
  out.flush();
  ISPLAT_CHECK(out.good(), path_, ": write failed (disk full or read-only?)");
}

std::vector<nlohmann::json> read_jsonl(const std::string& path,
                                       const std::function<void(int64_t, const std::string&)>& on_bad) {
  std::vector<nlohmann::json> records;
  std::ifstream in(path, std::ios::binary);
  if (!in.is_open()) return records;
  std::string line;
  int64_t lineno = 0;
  while (std::getline(in, line)) {
    ++lineno;
    if (line.empty()) continue;
    nlohmann::json j = nlohmann::json::parse(line, nullptr, /*allow_exceptions=*/false);
    if (j.is_discarded() || !j.is_object()) {
      if (on_bad) on_bad(lineno, j.is_discarded() ? "not valid JSON" : "not a JSON object");
      continue;
    }
    records.push_back(std::move(j));
  }
  return records;
}

}  // namespace isplat
