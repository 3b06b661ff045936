// Atomic file writes: write to a temporary file in the same folder, flush, then rename over the target.
#pragma once
#include <functional>
#include <ostream>
#include <string>

namespace isplat {

// Writes through `fill` into a temporary file, fsyncs it and renames it to `path`. On any failure the
// temporary is removed and the old `path` (if any) is untouched. Creates parent folders.
void write_file_atomic(const std::string& path, const std::function<void(std::ostream&)>& fill);
void write_file_atomic(const std::string& path, const std::string& bytes);

// For writers that need a file name (OpenCV, OpenEXR, HDF5): hands out a temporary path with the same
// extension; commit() renames it into place, the destructor removes it if commit() was not reached.
class AtomicPath {
 public:
  explicit AtomicPath(std::string path);
  ~AtomicPath();
  AtomicPath(const AtomicPath&) = delete;
  AtomicPath& operator=(const AtomicPath&) = delete;
  const std::string& temp() const { return temp_; }
  void commit();

 private:
  std::string path_, temp_;
  bool committed_ = false;
};

std::string read_file_bytes(const std::string& path);  // throws Error naming the path

// The identity of a file's content: its size and 64-bit FNV-1a hash as "<bytes>:<16 hex digits>". Tells a
// retrained checkpoint from the one scores were computed with when both sit at the same path.
std::string file_fingerprint(const std::string& path);

// Copies `from` to `to` atomically: a reflink (shared blocks, copy-on-write) where the file system has
// them, else a byte copy. Either way the two are separate files: writing one never changes the other.
void copy_file_atomic(const std::string& from, const std::string& to);

// Removes the temporaries that writes above leave behind when killed, in `dir` (not below). Only safe when
// no other process writes there (e.g. under the run folder's lock). Returns how many were removed.
int64_t remove_stale_temporaries(const std::string& dir);

}  // namespace isplat
