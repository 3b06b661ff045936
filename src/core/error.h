// The project's exception type and a tiny string builder for error messages.
#pragma once
#include <sstream>
#include <stdexcept>
#include <string>

namespace isplat {

// Concatenate anything streamable into one string: cat("key '", k, "' = ", v).
template <class... Args>
std::string cat(const Args&... args) {
  std::ostringstream os;
  (os << ... << args);
  return os.str();
}

// All user-facing failures (bad files, bad config, bad input) are thrown as Error.
// Messages name the file, key or value at fault.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& what) : std::runtime_error(what) {}
};

template <class... Args>
[[noreturn]] void fail(const Args&... args) {
  throw Error(cat(args...));
}

#define ISPLAT_CHECK(cond, ...)               \
  do {                                        \
    if (!(cond)) ::isplat::fail(__VA_ARGS__); \
  } while (0)

}  // namespace isplat
