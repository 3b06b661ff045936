// The executables' common failure path.
#include "core/app.h"

#include <c10/util/Exception.h>

#include <filesystem>
#include <new>
#include <sstream>

#include "core/error.h"
#include "core/log.h"
#include "core/runtime.h"

namespace isplat {

namespace {
// True when `message` holds one of the file names or paths in `context` (its words with a '/' or a '.').
bool names_any_path(const std::string& message, const std::string& context) {
  std::istringstream words(context);
  std::string w;
  while (words >> w) {
    while (!w.empty() && (w.back() == ';' || w.back() == ',')) w.pop_back();
    if (w.size() > 2 && w.find_first_of("/.") != std::string::npos && message.find(w) != std::string::npos) return true;
    const std::string base = w.substr(w.find_last_of('/') + 1);  // a path given relative in the message
    if (base.size() > 2 && base.find('.') != std::string::npos && message.find(base) != std::string::npos) return true;
  }
  return false;
}
}  // namespace

int run_main(const char* program, const std::function<int()>& body) {
  keep_freed_memory();
  ErrorContext::take();
  std::string message;
  bool is_own = false;
  try {
    return body();
  } catch (const Error& e) {
    message = e.what();
    is_own = true;
  } catch (const c10::Error& e) {  // a LibTorch check: its message without the C++ backtrace
    message = cat(program, ": LibTorch error: ", e.what_without_backtrace());
  } catch (const std::filesystem::filesystem_error& e) {  // names its path: "a read-only file system" is actionable
    message = cat(e.path1().string(), ": ", e.code().message(), " (", program, ": ", e.what(), ")");
  } catch (const std::bad_alloc&) {
    message = cat(program, ": out of memory");
  } catch (const std::exception& e) {
    message = cat(program, ": internal error: ", e.what());
  }
  // What was being done when it failed: the file, photo or step the user can act on. The project's own errors name
  // their file already; they get it only when they name nothing of it.
  const std::string context = ErrorContext::take();
  log_line(LogLevel::Error, context.empty() || (is_own && names_any_path(message, context))
                                ? message
                                : cat(message, " (while ", context, ")"));
  return 1;
}

}  // namespace isplat
