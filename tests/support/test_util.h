// Shared test helpers: a fresh temporary folder per test and the shared-weights location.
#pragma once
#include <functional>
#include <string>

#include "core/log.h"

namespace isplat::test {

// Warnings and errors only while in scope (generation and training are chatty); restores the level.
struct QuietLogs {
  LogLevel before = log_level();
  QuietLogs() { set_log_level(LogLevel::Warn); }
  ~QuietLogs() { set_log_level(before); }
  QuietLogs(const QuietLogs&) = delete;
  QuietLogs& operator=(const QuietLogs&) = delete;
};

// A new empty folder under $ISPLAT_TEST_TMP (or /tmp), unique per call.
std::string temp_dir(const std::string& tag);
// The weights shipped in the repository (<source>/weights).
std::string project_weights_dir();
// The shipped SqueezeNet-1.1 ImageNet features (the perceptual loss's, the encoder's and the prior's backbone).
std::string squeezenet_weights();
// Writes raw bytes to a file (for crafting corrupt inputs).
void write_bytes(const std::string& path, const std::string& bytes);
std::string read_bytes(const std::string& path);
// The message of the isplat::Error that `f` throws, or "<no error>".
std::string error_of(const std::function<void()>& f);

}  // namespace isplat::test
