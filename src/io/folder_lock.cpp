// FolderLock: flock(2) on a lock file that records the holder's pid.
#include "io/folder_lock.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

#include "core/error.h"

namespace isplat {
namespace {

std::string lock_path(const std::string& dir, const std::string& name = ".lock") {
  return (std::filesystem::path(dir) / name).string();
}

// The holder's pid as its lock file records it, "?" when the file holds none yet.
std::string recorded_pid(int fd) {
  char pid[32] = {0};
  const ssize_t n = ::pread(fd, pid, sizeof pid - 1, 0);
  return n > 0 ? std::string(pid, static_cast<size_t>(n)) : std::string("?");
}

}  // namespace

FolderLock::FolderLock(const std::string& dir, const std::string& name) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) fail(dir, ": cannot create the folder: ", ec.message());
  const std::string path = lock_path(dir, name);
  fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC | O_NOFOLLOW, 0644);
  if (fd_ < 0) fail(dir, ": cannot create the lock file ", path, ": ", std::strerror(errno));
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    const std::string holder = recorded_pid(fd_);
    ::close(fd_);
    fd_ = -1;
    if (err == EWOULDBLOCK)
      fail(dir, ": another process (pid ", holder,
           ") is writing into this folder; wait for it to finish or choose another output folder");
    fail(dir, ": cannot lock ", path, ": ", std::strerror(err));
  }
  const std::string me = std::to_string(::getpid());
  // The pid only serves a second process's message; the lock holds without it.
  if (::ftruncate(fd_, 0) == 0) (void)!::pwrite(fd_, me.data(), me.size(), 0);
}

std::string folder_lock_holder(const std::string& dir) {
  const int fd = ::open(lock_path(dir).c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
  if (fd < 0) return "";
  std::string holder;
  if (::flock(fd, LOCK_SH | LOCK_NB) != 0 && errno == EWOULDBLOCK) holder = recorded_pid(fd);
  ::close(fd);  // also releases the shared lock taken when nobody held it
  return holder;
}

FolderLock::~FolderLock() {
  if (fd_ >= 0) ::close(fd_);  // closing the descriptor releases the lock
}

}  // namespace isplat
