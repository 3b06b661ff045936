// Progress bar: ~10 redraws/s on a TTY; on pipes and CI logs, a line at each 10% or every 30 s.
#include "core/progress.h"

#include "core/log.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <sstream>

namespace isplat {

ProgressBar::ProgressBar(std::string label, int64_t total, std::string unit)
    : label_(std::move(label)),
      unit_(std::move(unit)),
      total_(std::max<int64_t>(0, total)),
      tty_(isatty(fileno(stderr)) != 0),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_) {}

ProgressBar::~ProgressBar() {
  finish();
}

void ProgressBar::tick(int64_t n) {
  set(done_ + n);
}

void ProgressBar::set(int64_t done) {
  done_ = done;
  maybe_draw(false);
}

void ProgressBar::postfix(const std::string& text) {
  postfix_ = text;
}

double ProgressBar::elapsed_seconds() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

std::string ProgressBar::format_duration(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return "?";
  auto s = static_cast<int64_t>(std::llround(seconds));
  char buf[32];
  if (s >= 3600)
    std::snprintf(buf, sizeof buf, "%lld:%02lld:%02lld", (long long)(s / 3600), (long long)(s / 60 % 60),
                  (long long)(s % 60));
  else
    std::snprintf(buf, sizeof buf, "%lld:%02lld", (long long)(s / 60), (long long)(s % 60));
  return buf;
}

std::string ProgressBar::status_line() const {
  const double t = elapsed_seconds();
  const double rate = t > 0 ? done_ / t : 0.0;
  std::ostringstream os;
  os << label_ << " ";
  if (total_ > 0) {
    const double frac = std::min(1.0, static_cast<double>(done_) / total_);
    const int width = 24, filled = static_cast<int>(frac * width);
    os << "[" << std::string(filled, '#') << std::string(width - filled, '.') << "] ";
    os << done_ << "/" << total_ << " " << static_cast<int>(frac * 100) << "% ";
  } else {
    os << done_ << " " << unit_ << " ";
  }
  char rbuf[48];
  if (rate >= 1.0 || rate == 0.0)
    std::snprintf(rbuf, sizeof rbuf, "%.1f %s/s", rate, unit_.c_str());
  else
    std::snprintf(rbuf, sizeof rbuf, "%.2f s/%s", 1.0 / rate, unit_.c_str());
  os << rbuf << " elapsed " << format_duration(t);
  if (total_ > 0 && done_ < total_) os << " ETA " << (rate > 0 ? format_duration((total_ - done_) / rate) : "?");
  if (!postfix_.empty()) os << " | " << postfix_;
  return os.str();
}

void ProgressBar::maybe_draw(bool force) {
  if (finished_ || log_level() > LogLevel::Info) return;  // quiet runs (and tests) get no bar
  if (force && done_ == last_drawn_done_) return;         // the final state is already on screen
  const auto now = std::chrono::steady_clock::now();
  const double since = std::chrono::duration<double>(now - last_draw_).count();
  if (tty_) {
    if (!force && since < 0.1) return;
    std::cerr << "\r\033[K" << status_line() << std::flush;
  } else {
    const int percent = total_ > 0 ? static_cast<int>(100.0 * done_ / total_) / 10 * 10 : -1;
    if (!force && percent == last_percent_line_ && since < 30.0) return;
    last_percent_line_ = percent;
    std::cerr << status_line() << '\n' << std::flush;
  }
  last_draw_ = now;
  last_drawn_done_ = done_;
}

void ProgressBar::finish() {
  if (finished_) return;
  maybe_draw(true);
  if (tty_) std::cerr << '\n' << std::flush;
  finished_ = true;
}

}  // namespace isplat
