// A progress bar with rate and ETA; redraws in place on a terminal, prints plain lines otherwise.
#pragma once
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <string>

namespace isplat {

// Wall-clock milliseconds since t0, for per-stage timings.
inline double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

class ProgressBar {
 public:
  // `total` may be 0 when unknown (then no ETA is shown). Output goes to stderr.
  ProgressBar(std::string label, int64_t total, std::string unit = "it");
  ~ProgressBar();
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  void tick(int64_t n = 1);
  void set(int64_t done);
  void postfix(const std::string& text);  // e.g. "loss 0.123"
  void finish();

  double elapsed_seconds() const;
  // Rendered status line (what is printed, without control characters); public for tests.
  std::string status_line() const;
  static std::string format_duration(double seconds);  // "1:05:09", "3:07", "0:04"

 private:
  void maybe_draw(bool force);

  std::string label_, unit_, postfix_;
  int64_t total_, done_ = 0;
  bool tty_, finished_ = false;
  std::chrono::steady_clock::time_point start_, last_draw_;
  int last_percent_line_ = -1;
  int64_t last_drawn_done_ = -1;
};

}  // namespace isplat
