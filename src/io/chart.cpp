// Minimal plotting: axes with "nice" ticks, tab10 colours, markers and a legend box.
#include "io/chart.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "io/image_io.h"

namespace isplat {
namespace {

// RGB order (write_image takes RGB): the matplotlib "tab10" palette.
const cv::Scalar kPalette[] = {{31, 119, 180}, {255, 127, 14},  {44, 160, 44},   {214, 39, 40},  {148, 103, 189},
                               {140, 86, 75},  {227, 119, 194}, {127, 127, 127}, {188, 189, 34}, {23, 190, 207}};

std::string label(double v) {
  std::ostringstream os;
  if (std::abs(v) >= 1e4 || (std::abs(v) < 1e-3 && v != 0))
    os.precision(2), os << std::scientific << v;
  else
    os.precision(4), os << v;
  return os.str();
}

// About `n` round tick values covering [lo, hi].
std::vector<double> ticks(double lo, double hi, int n = 5) {
  const double raw = (hi - lo) / n, mag = std::pow(10.0, std::floor(std::log10(raw)));
  double step = mag;
  for (double m : {1.0, 2.0, 2.5, 5.0, 10.0})
    if (m * mag >= raw) {
      step = m * mag;
      break;
    }
  std::vector<double> out;
  for (double t = std::ceil(lo / step) * step; t <= hi + 1e-9 * step; t += step)
    out.push_back(std::abs(t) < 1e-12 * step ? 0 : t);
  return out;
}

void draw_marker(cv::Mat& img, int kind, cv::Point p, const cv::Scalar& c) {
  switch (kind) {
    case 0:
      cv::circle(img, p, 5, c, cv::FILLED, cv::LINE_AA);
      break;
    case 1:
      cv::rectangle(img, {p.x - 4, p.y - 4}, {p.x + 4, p.y + 4}, c, cv::FILLED);
      break;
    case 2: {
      std::vector<cv::Point> tri = {{p.x, p.y - 6}, {p.x - 5, p.y + 4}, {p.x + 5, p.y + 4}};
      cv::fillConvexPoly(img, tri, c, cv::LINE_AA);
      break;
    }
    case 3:
      cv::drawMarker(img, p, c, cv::MARKER_TILTED_CROSS, 11, 2, cv::LINE_AA);
      break;
    default:
      break;
  }
}

cv::Mat draw_chart(const Chart& chart, int W, int H) {
  cv::Mat img(H, W, CV_8UC3, cv::Scalar(255, 255, 255));
  const cv::Scalar black(0, 0, 0), grid(225, 225, 225);
  auto text = [&](const std::string& s, cv::Point p, double scale = 0.42) {
    cv::putText(img, s, p, cv::FONT_HERSHEY_SIMPLEX, scale, black, 1, cv::LINE_AA);
  };
  const int L = 70, R = 20, T = 44, B = 48;
  text(chart.title, {L, 18}, 0.5);
  auto fx = [&](double x) { return chart.log_x ? std::log10(x) : x; };
  double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
  for (const auto& s : chart.series)
    for (size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i]) || (chart.log_x && s.x[i] <= 0)) continue;
      x0 = std::min(x0, fx(s.x[i])), x1 = std::max(x1, fx(s.x[i]));
      y0 = std::min(y0, s.y[i]), y1 = std::max(y1, s.y[i]);
    }
  cv::rectangle(img, {L, T}, {W - R, H - B}, black, 1);
  if (x0 > x1) {
    text("no data", {W / 2 - 30, H / 2});
    return img;
  }
  if (x1 - x0 < 1e-12) x0 -= 0.5, x1 += 0.5;
  if (y1 - y0 < 1e-12) y0 -= 0.5, y1 += 0.5;
  const double padx = 0.03 * (x1 - x0), pady = 0.06 * (y1 - y0);
  x0 -= padx, x1 += padx, y0 -= pady, y1 += pady;
  auto px = [&](double x) { return L + static_cast<int>((fx(x) - x0) / (x1 - x0) * (W - L - R)); };
  auto py = [&](double y) { return H - B - static_cast<int>((y - y0) / (y1 - y0) * (H - T - B)); };
  for (double t : ticks(y0, y1)) {
    cv::line(img, {L, py(t)}, {W - R, py(t)}, grid);
    text(label(t), {4, py(t) + 4});
  }
  if (chart.log_x) {
    for (int e = static_cast<int>(std::ceil(x0)); e <= static_cast<int>(std::floor(x1)); ++e) {
      const double v = std::pow(10.0, e);
      cv::line(img, {px(v), T}, {px(v), H - B}, grid);
      text(label(v), {px(v) - 14, H - B + 16});
    }
  } else {
    for (double t : ticks(x0, x1)) {
      cv::line(img, {px(t), T}, {px(t), H - B}, grid);
      text(label(t), {px(t) - 14, H - B + 16});
    }
  }
  cv::rectangle(img, {L, T}, {W - R, H - B}, black, 1);
  text(chart.x_label + (chart.log_x ? " (log)" : ""), {L + (W - L - R) / 2 - 60, H - 10});
  text(chart.y_label, {L, T - 4}, 0.4);
  int legend_y = T + 14;
  for (size_t k = 0; k < chart.series.size(); ++k) {
    const auto& s = chart.series[k];
    const cv::Scalar c = kPalette[(s.color >= 0 ? static_cast<size_t>(s.color) : k) % 10];
    cv::Point prev(-1, -1);
    for (size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i]) || (chart.log_x && s.x[i] <= 0)) {
        prev = {-1, -1};
        continue;
      }
      const cv::Point p(px(s.x[i]), py(s.y[i]));
      if (s.line && prev.x >= 0) cv::line(img, prev, p, c, 2, cv::LINE_AA);
      draw_marker(img, s.marker, p, c);
      prev = p;
    }
    // Legend entry, top right inside the axes.
    const int lx = W - R - 170;
    if (s.line) cv::line(img, {lx, legend_y - 4}, {lx + 18, legend_y - 4}, c, 2, cv::LINE_AA);
    draw_marker(img, s.marker >= 0 ? s.marker : -1, {lx + 9, legend_y - 4}, c);
    text(s.name.substr(0, 24), {lx + 24, legend_y}, 0.38);
    legend_y += 15;
  }
  return img;
}

}  // namespace

void write_charts(const std::string& path, const std::vector<Chart>& charts, int columns, int width, int height) {
  const int n = static_cast<int>(charts.size()), cols = std::max(1, std::min(columns, std::max(1, n)));
  const int rows = std::max(1, (n + cols - 1) / cols);
  cv::Mat canvas(rows * height, cols * width, CV_8UC3, cv::Scalar(255, 255, 255));
  for (int k = 0; k < n; ++k)
    draw_chart(charts[k], width, height)
        .copyTo(canvas(cv::Rect((k % cols) * width, (k / cols) * height, width, height)));
  write_image(path, canvas);  // 8-bit RGB
}

}  // namespace isplat
