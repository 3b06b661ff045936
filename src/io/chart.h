// Charts as PNG (OpenCV drawing): line and scatter series on linear or log axes, laid out in a grid.
// Used for training curves, experiment reports and speed/quality charts.
#pragma once
#include <string>
#include <vector>

namespace isplat {

struct ChartSeries {
  std::string name;
  std::vector<double> x, y;  // non-finite points are skipped
  bool line = true;          // connect the points
  int marker = -1;           // -1 none, 0 circle, 1 square, 2 triangle, 3 cross
  int color = -1;            // palette index (tab10); -1 = the series' position
};

struct Chart {
  std::string title, x_label, y_label;
  bool log_x = false;
  std::vector<ChartSeries> series;
};

// Writes the charts side by side, `columns` per row, each `width` x `height` pixels, with one legend per
// chart. Atomic; empty charts are drawn with a "no data" note.
void write_charts(const std::string& path, const std::vector<Chart>& charts, int columns = 2, int width = 640,
                  int height = 420);

}  // namespace isplat
