// Whole-string number parsing without exceptions escaping.
#include "core/parse.h"

namespace isplat {

std::optional<double> parse_double(const std::string& s) {
  size_t used = 0;
  try {
    const double v = std::stod(s, &used);
    if (used == s.size() && !s.empty()) return v;
  } catch (const std::exception&) {
  }
  return std::nullopt;
}

std::optional<int64_t> parse_int(const std::string& s) {
  size_t used = 0;
  try {
    const long long v = std::stoll(s, &used);
    if (used == s.size() && !s.empty()) return v;
  } catch (const std::exception&) {
  }
  return std::nullopt;
}

}  // namespace isplat
