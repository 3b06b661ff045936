// Shipped-file lookup: working directory first, then the folders above the executable.
#include "core/paths.h"

#include <cctype>
#include <filesystem>

#include "core/error.h"

namespace isplat {
namespace fs = std::filesystem;

std::string resolve_shipped_path(const std::string& path) {
  std::error_code ec;
  if (path.empty() || fs::path(path).is_absolute() || fs::exists(path, ec)) return path;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec) return path;
  for (fs::path dir = exe.parent_path(); !dir.empty(); dir = dir.parent_path()) {
    if (fs::exists(dir / path, ec)) return (dir / path).string();
    if (dir == dir.root_path()) break;
  }
  return path;
}

std::string safe_name(const std::string& name) {
  std::string out = name.empty() ? "_" : name;
  for (char& c : out)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_') c = '_';
  return out;
}

void require_regular_file(const std::string& path, const char* kind) {
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (ec && ec != std::errc::no_such_file_or_directory) {
    if (ec == std::errc::too_many_symbolic_link_levels) fail(path, ": symbolic link loop, not a regular ", kind);
    fail(path, ": cannot read: ", ec.message());
  }
  switch (st.type()) {
    case fs::file_type::regular:
      return;
    case fs::file_type::not_found:
      // A dangling link exists but leads nowhere: say so, not just "no such file".
      if (fs::is_symlink(fs::symlink_status(path, ec))) fail(path, ": symbolic link to a missing file");
      fail(path, ": no such file");
    case fs::file_type::directory:
      fail(path, ": is a folder, not a regular ", kind);
    case fs::file_type::character:
    case fs::file_type::block:
      fail(path, ": is a device, not a regular ", kind);
    case fs::file_type::fifo:
      fail(path, ": is a FIFO (named pipe), not a regular ", kind);
    case fs::file_type::socket:
      fail(path, ": is a socket, not a regular ", kind);
    default:
      fail(path, ": is not a regular ", kind);
  }
}

}  // namespace isplat
