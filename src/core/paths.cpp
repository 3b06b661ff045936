// Shipped-file lookup: working directory first, then the folders above the executable.
#include "core/paths.h"

#include <cctype>
#include <filesystem>

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

}  // namespace isplat
