// An exclusive lock on an output folder, so two processes never write one run at the same time.
#pragma once
#include <string>

namespace isplat {

// flock on <dir>/.lock, holding the owner's pid. A second holder fails at once with an Error naming the
// folder and the pid that holds it. The kernel drops the lock when the process ends, however it ends.
// `name` other than ".lock" gives writers of disjoint files in one folder (an evaluation's shards) a lock each.
class FolderLock {
 public:
  explicit FolderLock(const std::string& dir, const std::string& name = ".lock");
  ~FolderLock();
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;

 private:
  int fd_ = -1;
};

// The pid (as the lock file records it, "?" if unreadable) of the process that holds <dir>/.lock, or "" when none
// does: no lock file, or its holder has ended.
std::string folder_lock_holder(const std::string& dir);

}  // namespace isplat
