// The pretrained-weights lookup: environment, checkout, user cache, in that order.
#include "core/weights.h"

#include <cstdlib>
#include <filesystem>

#include "core/error.h"
#include "core/paths.h"

namespace isplat {
namespace fs = std::filesystem;

namespace {

bool is_dir(const fs::path& p) {
  std::error_code ec;
  return fs::is_directory(p, ec);
}

// The checkout's weights/: beside the working directory, else above the running executable (build/tool), where a
// checkout is recognised by its weights/README.md, so an unrelated folder named weights is not taken.
fs::path checkout_weights() {
  std::error_code ec;
  if (is_dir("weights")) return fs::absolute("weights", ec);
  const fs::path readme = resolve_shipped_path("weights/README.md");
  return fs::exists(readme, ec) ? readme.parent_path() : fs::path();
}

bool bare_name(const std::string& value) {
  const fs::path p(value);
  if (!p.has_parent_path()) return true;
  // The form the shipped configs and older checkpoints used: "weights/<name>".
  std::error_code ec;
  return p.parent_path() == "weights" && !fs::exists(p, ec);
}

}  // namespace

std::vector<std::string> weights_search_path() {
  std::vector<fs::path> candidates;
  if (const char* env = std::getenv(kWeightsEnv); env && *env) candidates.emplace_back(env);
  candidates.push_back(checkout_weights());
  if (const char* home = std::getenv("HOME"); home && *home)
    candidates.push_back(fs::path(home) / ".cache" / "infinisplat" / "weights");
  std::vector<std::string> out;
  for (const auto& c : candidates)
    if (!c.empty() && is_dir(c)) out.push_back(c.string());
  return out;
}

std::string find_weights_file(const std::string& name_or_path) {
  if (name_or_path.empty() || !bare_name(name_or_path)) return name_or_path;
  const fs::path name = fs::path(name_or_path).filename();
  std::error_code ec;
  for (const auto& dir : weights_search_path())
    if (fs::is_regular_file(fs::path(dir) / name, ec)) return (fs::path(dir) / name).string();
  return "";
}

std::string find_weights_folder(const std::vector<std::string>& files) {
  std::error_code ec;
  for (const auto& dir : weights_search_path()) {
    bool all = true;
    for (const auto& f : files) all = all && fs::is_regular_file(fs::path(dir) / f, ec);
    if (all) return dir;
  }
  return "";
}

std::string missing_weights_hint() {
  const char* env = std::getenv(kWeightsEnv);
  return cat("searched $", kWeightsEnv, (env && *env) ? cat(" (", env, ")") : std::string(" (unset)"),
             ", the checkout's weights/ and ~/.cache/infinisplat/weights; run ", kGetWeightsCommand,
             " to download, convert and verify them");
}

}  // namespace isplat
