// Small line charts as PNG (through OpenCV) for reports: a few named series over one x axis,
// with axes, tick labels and a legend. Tools only.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "rt/expected.hpp"

namespace stac::pictures {

struct ChartSeries {
  std::string name;
  std::vector<double> x, y;  // same length
};

struct Chart {
  std::string title, x_label, y_label;
  std::vector<ChartSeries> series;
  int width_px = 800, height_px = 420;
  double y_min = 0.0;  // the y axis' lower end (the upper one comes from the data)
};

// Writes the chart; fails naming the file when it cannot be written.
rt::Status save_chart(const Chart& chart, const std::filesystem::path& png);

}  // namespace stac::pictures
