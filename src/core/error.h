// The project's exception type and a tiny string builder for error messages.
#pragma once
#include <exception>
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

// What the program was doing, for failures that cannot name it themselves (a LibTorch check, out of memory, an
// OpenCV exception). A scope that an exception leaves records its description; the executables' failure path
// (run_main) prints the innermost first: "out of memory (while predicting photo.jpg at 4096x3072; ...)". Cheap
// enough per file or per photo, not per pixel.
class ErrorContext {
 public:
  template <class... Args>
  explicit ErrorContext(const Args&... args) : what_(cat(args...)), in_flight_(std::uncaught_exceptions()) {
    if (in_flight_ == 0) unwound().clear();  // a new piece of work: an earlier, handled failure is not its story
  }
  ~ErrorContext() {
    if (std::uncaught_exceptions() <= in_flight_) return;
    try {  // never throw while unwinding (out of memory, of all failures, may land here)
      unwound() += (unwound().empty() ? "" : "; ") + what_;
    } catch (...) {
    }
  }
  ErrorContext(const ErrorContext&) = delete;
  ErrorContext& operator=(const ErrorContext&) = delete;
  // The contexts the last exception left, innermost first ("" when none); cleared by taking.
  static std::string take() {
    std::string s;
    s.swap(unwound());
    return s;
  }

 private:
  static std::string& unwound() {
    thread_local std::string s;
    return s;
  }
  std::string what_;
  int in_flight_;
};

#define ISPLAT_CHECK(cond, ...)               \
  do {                                        \
    if (!(cond)) ::isplat::fail(__VA_ARGS__); \
  } while (0)

}  // namespace isplat
