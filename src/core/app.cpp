// The executables' common failure path.
#include "core/app.h"

#include <c10/util/Exception.h>

#include <new>

#include "core/error.h"
#include "core/log.h"
#include "core/runtime.h"

namespace isplat {

int run_main(const char* program, const std::function<int()>& body) {
  keep_freed_memory();
  try {
    return body();
  } catch (const Error& e) {
    log_line(LogLevel::Error, e.what());
  } catch (const c10::Error& e) {  // a LibTorch check: its message without the C++ backtrace
    log_line(LogLevel::Error, cat(program, ": LibTorch error: ", e.what_without_backtrace()));
  } catch (const std::bad_alloc&) {
    log_line(LogLevel::Error, cat(program, ": out of memory"));
  } catch (const std::exception& e) {
    log_line(LogLevel::Error, cat(program, ": internal error: ", e.what()));
  }
  return 1;
}

}  // namespace isplat
