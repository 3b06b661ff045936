// JSON-lines append and read with per-record flush checks and tolerant reading.
#include "io/jsonl.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "core/config.h"
#include "core/error.h"

namespace isplat {
namespace fs = std::filesystem;

namespace {
// Appends `text` in full or throws. O_NOFOLLOW: a symlink planted in an output folder must not redirect
// our appends to a file elsewhere.
void append_text(const std::string& path, const std::string& text) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_APPEND | O_CREAT | O_CLOEXEC | O_NOFOLLOW, 0644);
  if (fd < 0) {
    if (errno == ELOOP) fail(path, ": is a symbolic link; refusing to append through it");
    fail(path, ": cannot open for appending: ", std::strerror(errno));
  }
  size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const std::string why = n < 0 ? std::strerror(errno) : "no progress";
      ::close(fd);
      fail(path, ": write failed (disk full or read-only?): ", why);
    }
    done += static_cast<size_t>(n);
  }
  if (::close(fd) != 0) fail(path, ": write failed (disk full or read-only?): ", std::strerror(errno));
}
}  // namespace

JsonlWriter::JsonlWriter(std::string path) : path_(std::move(path)) {
  std::error_code ec;
  if (fs::is_symlink(path_, ec)) fail(path_, ": is a symbolic link; refusing to append through it");
  if (!fs::exists(path_, ec) || fs::file_size(path_, ec) == 0) return;
  std::ifstream in(path_, std::ios::binary);
  in.seekg(-1, std::ios::end);
  char last = '\n';
  in.get(last);
  if (last != '\n') append_text(path_, "\n");  // a record cut short by a kill: end it so the next starts afresh
}

void JsonlWriter::write(const nlohmann::json& record) {
  append_text(path_, record.dump() + "\n");
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
    nlohmann::json j;
    try {
      j = parse_json(line, path);  // bounded nesting: a hostile line cannot exhaust the stack
    } catch (const Error&) {
      if (on_bad) on_bad(lineno, "not valid JSON");
      continue;
    }
    if (!j.is_object()) {
      if (on_bad) on_bad(lineno, "not a JSON object");
      continue;
    }
    records.push_back(std::move(j));
  }
  return records;
}

}  // namespace isplat
