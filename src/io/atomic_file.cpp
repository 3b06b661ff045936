// Atomic writes (temp + fsync + rename) and whole-file reads with clear errors.
#include "io/atomic_file.h"

#include <fcntl.h>
#include <linux/fs.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "core/error.h"

namespace isplat {
namespace fs = std::filesystem;

// Temporaries are ".<stem>.tmp<pid>_<n><ext>" beside the target; remove_stale_temporaries matches this.
static const char* const kTempMarker = ".tmp";

static std::string temp_name_for(const std::string& path) {
  static std::atomic<uint64_t> counter{0};
  fs::path p(path);
  const std::string stem = p.stem().string(), ext = p.extension().string();
  return (p.parent_path() / cat(".", stem, kTempMarker, getpid(), "_", counter++, ext)).string();
}

static void ensure_parent(const std::string& path) {
  fs::path parent = fs::path(path).parent_path();
  if (parent.empty()) return;
  std::error_code ec;
  fs::create_directories(parent, ec);
  if (ec) fail(path, ": cannot create folder ", parent.string(), ": ", ec.message());
}

static void fsync_path(const std::string& path) {
  int fd = ::open(path.c_str(), O_RDONLY);
  if (fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
}

static void rename_into_place(const std::string& temp, const std::string& path) {
  if (std::rename(temp.c_str(), path.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    std::remove(temp.c_str());
    fail(path, ": cannot rename temporary file into place: ", why);
  }
}

void write_file_atomic(const std::string& path, const std::function<void(std::ostream&)>& fill) {
  ensure_parent(path);
  const std::string temp = temp_name_for(path);
  try {
    {
      std::ofstream out(temp, std::ios::binary | std::ios::trunc);
      if (!out) fail(path, ": cannot open for writing: ", std::strerror(errno));
      fill(out);
      out.flush();
      if (!out) fail(path, ": write failed (disk full?)");
    }
    fsync_path(temp);
  } catch (...) {
    std::remove(temp.c_str());
    throw;
  }
  rename_into_place(temp, path);
}

void write_file_atomic(const std::string& path, const std::string& bytes) {
  write_file_atomic(path,
                    [&](std::ostream& os) { os.write(bytes.data(), static_cast<std::streamsize>(bytes.size())); });
}

AtomicPath::AtomicPath(std::string path) : path_(std::move(path)) {
  ensure_parent(path_);
  temp_ = temp_name_for(path_);
}

AtomicPath::~AtomicPath() {
  if (!committed_) std::remove(temp_.c_str());
}

void AtomicPath::commit() {
  if (!fs::exists(temp_)) fail(path_, ": writer produced no file");
  fsync_path(temp_);
  rename_into_place(temp_, path_);
  committed_ = true;
}

std::string read_file_bytes(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) fail(path, ": no such file");
  if (fs::is_directory(path, ec)) fail(path, ": is a folder, not a file");
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, ": cannot open: ", std::strerror(errno));
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) fail(path, ": read error");
  return ss.str();
}

std::string file_fingerprint(const std::string& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) fail(path, ": no such file");
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, ": cannot open: ", std::strerror(errno));
  uint64_t h = 14695981039346656037ull;  // FNV-1a offset basis
  uint64_t bytes = 0;
  std::vector<char> buf(1 << 20);
  while (in) {
    in.read(buf.data(), static_cast<std::streamsize>(buf.size()));
    const std::streamsize got = in.gcount();
    for (std::streamsize i = 0; i < got; ++i) h = (h ^ static_cast<unsigned char>(buf[i])) * 1099511628211ull;
    bytes += static_cast<uint64_t>(got);
  }
  if (in.bad()) fail(path, ": read error");
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
  return std::to_string(bytes) + ":" + hex;
}

void copy_file_atomic(const std::string& from, const std::string& to) {
  AtomicPath target(to);
  const int src = ::open(from.c_str(), O_RDONLY | O_CLOEXEC);
  if (src < 0) fail(from, ": cannot open for copying: ", std::strerror(errno));
  const int dst = ::open(target.temp().c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (dst < 0) {
    const std::string why = std::strerror(errno);
    ::close(src);
    fail(to, ": cannot create: ", why);
  }
  const bool cloned = ::ioctl(dst, FICLONE, src) == 0;
  ::close(src);
  ::close(dst);
  if (!cloned) {
    std::error_code ec;
    fs::copy_file(from, target.temp(), fs::copy_options::overwrite_existing, ec);
    if (ec) fail(to, ": cannot copy from ", from, ": ", ec.message());
  }
  target.commit();
}

int64_t remove_stale_temporaries(const std::string& dir) {
  int64_t removed = 0;
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.size() > 1 && name[0] == '.' && name.find(kTempMarker) != std::string::npos && it->is_regular_file(ec) &&
        fs::remove(it->path(), ec))
      ++removed;
  }
  return removed;
}

}  // namespace isplat
