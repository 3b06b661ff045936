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

}  // namespace isplat
