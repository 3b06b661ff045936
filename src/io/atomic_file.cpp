// Atomic writes (temp + fsync + rename) and whole-file reads with clear errors.
#include "io/atomic_file.h"

#include <fcntl.h>
#include <linux/fs.h>
#include <signal.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <atomic>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "core/error.h"
#include "core/paths.h"

namespace isplat {
namespace fs = std::filesystem;

// Temporaries are ".<stem>.isplat-tmp<pid>_<n><ext>" beside the target; is_temporary_name matches exactly this.
static const char* const kTempMarker = ".isplat-tmp";

namespace {
// The temporaries that exist now, for the signal handler: fixed slots (no allocation in the handler). A slot is
// 0 free, 1 being filled, 2 live. A temporary that finds no free slot is still removed on failure, only not on a
// signal.
constexpr int kSlots = 64;
constexpr size_t kSlotPath = 4096;
struct TempSlot {
  std::atomic<int> state{0};
  char path[kSlotPath];
};
TempSlot g_slots[kSlots];
std::atomic<int> g_signals{0};         // signals received since remove_temporaries_on_signal()
std::atomic<int> g_first_signal{0};    // the first of them
std::atomic<bool> g_graceful{false};   // the first signal only asks to stop
std::atomic<int> g_holding{0};         // commit_together() is renaming: signals wait for it
std::atomic<int> g_pending_signal{0};  // the signal that arrived while holding

int register_temp(const std::string& path) {
  if (path.size() >= kSlotPath) return -1;
  for (int i = 0; i < kSlots; ++i) {
    int expected = 0;
    if (g_slots[i].state.compare_exchange_strong(expected, 1)) {
      std::memcpy(g_slots[i].path, path.c_str(), path.size() + 1);
      g_slots[i].state.store(2);
      return i;
    }
  }
  return -1;
}

void unregister_temp(int slot) {
  if (slot >= 0) g_slots[slot].state.store(0);
}

[[noreturn]] void remove_temps_and_die(int sig) {
  for (auto& slot : g_slots)
    if (slot.state.load() == 2) ::unlink(slot.path);
  struct sigaction dfl {};
  dfl.sa_handler = SIG_DFL;
  sigemptyset(&dfl.sa_mask);
  ::sigaction(sig, &dfl, nullptr);
  ::raise(sig);
  ::_exit(128 + sig);  // not reached: the default action ends the process
}

void on_signal(int sig) {
  const int seen = g_signals.fetch_add(1);
  if (seen == 0) g_first_signal.store(sig);
  if (g_holding.load() > 0) {  // commit_together finishes its renames, then acts on it
    g_pending_signal.store(sig);
    return;
  }
  if (g_graceful.load() && seen == 0) return;  // interrupt_signal(): the loop stops at its next step
  remove_temps_and_die(sig);
}
}  // namespace

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
  const int slot = register_temp(temp);
  struct Unregister {
    int slot;
    ~Unregister() { unregister_temp(slot); }
  } unregister{slot};
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
  slot_ = register_temp(temp_);
}

AtomicPath::~AtomicPath() {
  if (!committed_) std::remove(temp_.c_str());
  unregister_temp(slot_);
}

void AtomicPath::commit() {
  if (!fs::exists(temp_)) fail(path_, ": writer produced no file");
  fsync_path(temp_);
  rename_into_place(temp_, path_);
  committed_ = true;
  unregister_temp(slot_);
  slot_ = -1;
}

void commit_together(const std::vector<AtomicPath*>& outputs) {
  for (AtomicPath* o : outputs)  // every file is whole before any target changes
    if (!fs::exists(o->temp())) fail(o->path(), ": writer produced no file");
  g_holding.fetch_add(1);
  std::string error;
  for (AtomicPath* o : outputs) try {
      o->commit();
    } catch (const Error& e) {
      error = e.what();
      break;
    }
  g_holding.fetch_sub(1);
  if (const int sig = g_pending_signal.exchange(0); sig != 0 && g_holding.load() == 0) {
    if (!g_graceful.load() || g_signals.load() > 1) remove_temps_and_die(sig);
  }
  if (!error.empty()) {
    std::string names;
    for (const AtomicPath* o : outputs) names += (names.empty() ? "" : ", ") + o->path();
    fail(error, " (writing ", names, " together)");
  }
}

void remove_temporaries_on_signal(bool graceful) {
  g_graceful = graceful;
  g_signals = 0;
  g_first_signal = 0;
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;
  for (int sig : {SIGINT, SIGTERM}) ::sigaction(sig, &sa, nullptr);
}

int interrupt_signal() {
  return g_first_signal.load();
}

bool is_temporary_name(const std::string& name, long* pid) {
  const size_t at = name.rfind(kTempMarker);
  if (name.size() < 2 || name[0] != '.' || at == std::string::npos || at < 1) return false;
  size_t i = at + std::strlen(kTempMarker);
  const size_t pid_start = i;
  while (i < name.size() && std::isdigit(static_cast<unsigned char>(name[i]))) ++i;
  if (i == pid_start || i - pid_start > 10 || i >= name.size() || name[i] != '_') return false;
  const long writer = std::stol(name.substr(pid_start, i - pid_start));
  const size_t n_start = ++i;
  while (i < name.size() && std::isdigit(static_cast<unsigned char>(name[i]))) ++i;
  if (i == n_start) return false;
  const std::string ext = name.substr(i);  // "" or ".ext", as std::filesystem's extension()
  if (!ext.empty() && (ext[0] != '.' || ext.find('.', 1) != std::string::npos)) return false;
  if (pid) *pid = writer;
  return true;
}

void refuse_output_over_input(const std::string& command, const NamedPath& output,
                              const std::vector<NamedPath>& inputs) {
  std::error_code ec;
  const fs::path out = fs::weakly_canonical(output.path, ec);
  for (const NamedPath& in : inputs) {
    if (in.path.empty() || output.path.empty()) continue;
    std::error_code e1, e2;
    const fs::path source = fs::weakly_canonical(in.path, e1);
    bool same = !ec && !e1 && out == source;
    // Another name for the same file (a hard link, a symlinked folder): the same device and inode.
    if (!same && fs::exists(output.path, e2) && fs::exists(in.path, e2))
      same = fs::equivalent(output.path, in.path, e2);
    if (same)
      fail(command, ": ", output.option, " ", output.path, " is the same file as ", in.option, " ", in.path,
           "; writing it would overwrite that input (choose another ", output.option, ")");
  }
}

std::string read_file_bytes(const std::string& path) {
  require_regular_file(path);  // a device or FIFO given as an input would never end or block
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
    long pid = 0;
    if (!is_temporary_name(it->path().filename().string(), &pid)) continue;
    // Only a writer that has ended: a live one (another process, or this one) may still rename it into place.
    const bool ended =
        pid > 0 && pid != static_cast<long>(getpid()) && ::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH;
    if (ended && it->is_regular_file(ec) && fs::remove(it->path(), ec)) ++removed;
  }
  return removed;
}

}  // namespace isplat
