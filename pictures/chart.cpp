#include "pictures/chart.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <iterator>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace stac::pictures {
namespace {

// A "nice" tick step (1, 2 or 5 times a power of ten) for about `count` ticks over `span`.
double tick_step(double span, int count) {
  const double raw = span / count;
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    if (m * p >= raw) return m * p;
  }
  return 10.0 * p;
}

std::string label(double v) {
  char b[32];
  std::snprintf(b, sizeof(b), "%g", std::abs(v) < 1e-12 ? 0.0 : v);
  return b;
}

}  // namespace

rt::Status save_chart(const Chart& chart, const std::filesystem::path& png) {
  const cv::Scalar colours[] = {
      {200, 120, 40}, {40, 110, 230}, {60, 170, 60}, {150, 60, 160}};  // BGR
  cv::Mat img(chart.height_px, chart.width_px, CV_8UC3, cv::Scalar(255, 255, 255));
  const int left = 70, right = 20, top = 40, bottom = 50;
  const int w = chart.width_px - left - right, h = chart.height_px - top - bottom;
  double x0 = 1e300, x1 = -1e300, y1 = 0.0;
  for (const auto& s : chart.series) {
    for (std::size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
      x0 = std::min(x0, s.x[i]);
      x1 = std::max(x1, s.x[i]);
      y1 = std::max(y1, s.y[i]);
    }
  }
  if (!(x1 > x0)) x1 = x0 + 1.0;
  const double y0 = chart.y_min;
  if (!(y1 > y0)) y1 = y0 + 1.0;
  const double ys = tick_step((y1 - y0) * 1.05, 5);
  y1 = y0 + std::ceil((y1 - y0) * 1.05 / ys) * ys;
  auto px = [&](double x, double y) {
    return cv::Point(left + static_cast<int>(std::lround((x - x0) / (x1 - x0) * w)),
                     top + h - static_cast<int>(std::lround((y - y0) / (y1 - y0) * h)));
  };
  const cv::Scalar grey(200, 200, 200), dark(60, 60, 60);
  for (double y = y0; y <= y1 + 1e-9; y += ys) {
    cv::line(img, px(x0, y), px(x1, y), grey, 1);
    cv::putText(img, label(y), px(x0, y) + cv::Point(-60, 4), cv::FONT_HERSHEY_SIMPLEX, 0.4, dark,
                1, cv::LINE_AA);
  }
  const double xs = tick_step(x1 - x0, 8);
  for (double x = std::ceil(x0 / xs) * xs; x <= x1 + 1e-9; x += xs) {
    cv::line(img, px(x, y0), px(x, y0) + cv::Point(0, 5), dark, 1);
    cv::putText(img, label(x), px(x, y0) + cv::Point(-10, 20), cv::FONT_HERSHEY_SIMPLEX, 0.4, dark,
                1, cv::LINE_AA);
  }
  cv::rectangle(img, cv::Point(left, top), cv::Point(left + w, top + h), dark, 1);
  cv::putText(img, chart.title, {left, 25}, cv::FONT_HERSHEY_SIMPLEX, 0.55, cv::Scalar(0, 0, 0), 1,
              cv::LINE_AA);
  cv::putText(img, chart.x_label, {left + w / 2 - 60, chart.height_px - 12},
              cv::FONT_HERSHEY_SIMPLEX, 0.45, dark, 1, cv::LINE_AA);
  cv::putText(img, chart.y_label, {5, top - 8}, cv::FONT_HERSHEY_SIMPLEX, 0.4, dark, 1,
              cv::LINE_AA);
  // The legend goes in the corner of the plot that the lines cross least (sampled every 2 px),
  // on white, so that no line runs under its text.
  std::size_t longest = 0;
  for (const auto& s : chart.series) longest = std::max(longest, s.name.size());
  const int legend_w = std::min(40 + 9 * static_cast<int>(longest), w);
  const int legend_h = std::min(8 + 18 * static_cast<int>(chart.series.size()), h);
  const cv::Rect corners[] = {{left + w - legend_w, top, legend_w, legend_h},
                              {left + w - legend_w, top + h - legend_h, legend_w, legend_h},
                              {left, top + h - legend_h, legend_w, legend_h},
                              {left, top, legend_w, legend_h}};
  std::size_t best = 0, best_hits = SIZE_MAX;
  for (std::size_t corner = 0; corner < std::size(corners); ++corner) {
    std::size_t hits = 0;
    for (const auto& s : chart.series) {
      for (std::size_t i = 1; i < s.x.size() && i < s.y.size(); ++i) {
        cv::Point a = px(s.x[i - 1], s.y[i - 1]), b = px(s.x[i], s.y[i]);
        // Only what is drawn inside the plot counts (and a point far outside costs nothing).
        if (!cv::clipLine(cv::Rect(left, top, w + 1, h + 1), a, b)) continue;
        const int steps = std::max(1, static_cast<int>(cv::norm(b - a) / 2.0));
        for (int t = 0; t <= steps; ++t) {
          const double f = static_cast<double>(t) / steps;
          const cv::Point p(static_cast<int>(std::lround(a.x + f * (b.x - a.x))),
                            static_cast<int>(std::lround(a.y + f * (b.y - a.y))));
          hits += corners[corner].contains(p) ? 1 : 0;
        }
      }
    }
    if (hits < best_hits) best_hits = hits, best = corner;
  }
  for (std::size_t k = 0; k < chart.series.size(); ++k) {
    const auto& s = chart.series[k];
    const cv::Scalar c = colours[k % 4];
    for (std::size_t i = 1; i < s.x.size() && i < s.y.size(); ++i) {
      cv::line(img, px(s.x[i - 1], s.y[i - 1]), px(s.x[i], s.y[i]), c, 2, cv::LINE_AA);
    }
  }
  const cv::Rect box = corners[best];
  cv::rectangle(img, box, cv::Scalar(255, 255, 255), cv::FILLED);
  cv::rectangle(img, box, grey, 1);
  for (std::size_t k = 0; k < chart.series.size(); ++k) {
    const auto& s = chart.series[k];
    const cv::Scalar c = colours[k % 4];
    const cv::Point at(box.x + 6, box.y + 13 + 18 * static_cast<int>(k));
    cv::line(img, at, at + cv::Point(25, 0), c, 3);
    cv::putText(img, s.name, at + cv::Point(32, 5), cv::FONT_HERSHEY_SIMPLEX, 0.45,
                cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  }
  try {
    if (!cv::imwrite(png.string(), img, {cv::IMWRITE_PNG_COMPRESSION, 9}))
      return rt::make_error(png.string() + ": cannot write the chart");
  } catch (const cv::Exception& e) {
    return rt::make_error(png.string() + ": cannot write the chart: " + e.what());
  }
  return {};
}

}  // namespace stac::pictures
