// Levelled logging to stderr; one mutex keeps lines from interleaving across threads.
#include "core/log.h"

#include <atomic>
#include <iostream>
#include <mutex>

namespace isplat {
namespace {
std::atomic<int> g_level{static_cast<int>(LogLevel::Info)};
std::mutex g_mutex;
}  // namespace

void set_log_level(LogLevel level) {
  g_level = static_cast<int>(level);
}
LogLevel log_level() {
  return static_cast<LogLevel>(g_level.load());
}

void log_line(LogLevel level, const std::string& message) {
  static const char* tags[] = {"[debug] ", "", "[warning] ", "[error] ", ""};
  std::lock_guard<std::mutex> lock(g_mutex);
  std::cerr << tags[static_cast<int>(level)] << message << '\n';
  std::cerr.flush();
}

}  // namespace isplat
