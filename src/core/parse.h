// Strict number parsing for text formats (CSV, COLMAP, command lines): the whole string must be a number.
#pragma once
#include <cstdint>
#include <optional>
#include <string>

namespace isplat {

std::optional<double> parse_double(const std::string& s);
std::optional<int64_t> parse_int(const std::string& s);

}  // namespace isplat
