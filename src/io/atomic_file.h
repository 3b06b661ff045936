// Atomic file writes: write to a temporary file in the same folder, flush, then rename over the target.
#pragma once
#include <functional>
#include <ostream>
#include <string>
#include <vector>

namespace isplat {

// Writes through `fill` into a temporary file, fsyncs it and renames it to `path`. On any failure the
// temporary is removed and the old `path` (if any) is untouched. Creates parent folders.
void write_file_atomic(const std::string& path, const std::function<void(std::ostream&)>& fill);
void write_file_atomic(const std::string& path, const std::string& bytes);

// For writers that need a file name (OpenCV, OpenEXR, HDF5), or outputs that must appear together: hands out a
// temporary path with the same extension; commit() renames it into place, the destructor removes it if commit()
// was not reached.
class AtomicPath {
 public:
  explicit AtomicPath(std::string path);
  ~AtomicPath();
  AtomicPath(const AtomicPath&) = delete;
  AtomicPath& operator=(const AtomicPath&) = delete;
  const std::string& path() const { return path_; }
  const std::string& temp() const { return temp_; }
  void commit();

 private:
  std::string path_, temp_;
  int slot_ = -1;  // in the table remove_temporaries_on_signal() empties
  bool committed_ = false;
};

// Commits finished temporaries in order with SIGINT and SIGTERM held off, so a signal never lands between two
// renames: outputs that belong together (a PLY and its camera JSON) appear together. Temporaries are written
// whole before anything is renamed, so a full disk fails before any target changes.
void commit_together(const std::vector<AtomicPath*>& outputs);

// Every write above registers its temporary while it exists. After this call, SIGINT and SIGTERM remove the
// registered temporaries and end the process as the signal would have (a shell reads 128 + signal). With
// `graceful`, the first signal is only recorded in interrupt_signal(), for loops that finish what they have
// (render's video); a second signal removes the temporaries and ends the process.
void remove_temporaries_on_signal(bool graceful = false);
int interrupt_signal();  // the first SIGINT or SIGTERM received since, 0 when none

// A temporary's name: ".<stem>.isplat-tmp<pid>_<n><ext>" beside the target. True when `name` (a file name, no
// folder) is exactly such a name, with its writer's pid in `pid`.
bool is_temporary_name(const std::string& name, long* pid = nullptr);

// Fails, naming both options and files, when the file `output` would be written to (its path or, when it
// exists, its inode) is one of `inputs` (option, path): a command never overwrites what it reads.
struct NamedPath {
  std::string option, path;
};
void refuse_output_over_input(const std::string& command, const NamedPath& output,
                              const std::vector<NamedPath>& inputs);

std::string read_file_bytes(const std::string& path);  // throws Error naming the path

// The identity of a file's content: its size and 64-bit FNV-1a hash as "<bytes>:<16 hex digits>". Tells a
// retrained checkpoint from the one scores were computed with when both sit at the same path.
std::string file_fingerprint(const std::string& path);

// Copies `from` to `to` atomically: a reflink (shared blocks, copy-on-write) where the file system has
// them, else a byte copy. Either way the two are separate files: writing one never changes the other.
void copy_file_atomic(const std::string& from, const std::string& to);

// Removes the temporaries that writes above leave behind when killed, in `dir` (not below): only names that are
// exactly is_temporary_name()'s, of a writer process that has ended. Files of other names (a user's
// ".draft.tmp.txt") are never touched. Returns how many were removed.
int64_t remove_stale_temporaries(const std::string& dir);

}  // namespace isplat
