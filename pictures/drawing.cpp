#include "pictures/drawing.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "pictures/png.hpp"

namespace stac::pictures {

rt::Status write_png(const std::filesystem::path& png, const cv::Mat& img,
                     const std::vector<int>& params) {
  try {
    if (!cv::imwrite(png.string(), img, params)) {
      return rt::make_error(png.string() + ": cannot write the picture (is the folder there?)");
    }
  } catch (const cv::Exception& e) {
    return rt::make_error(png.string() + ": cannot write the picture: " + e.what());
  }
  return {};
}

bool pictures_built() noexcept {
  return true;
}

Bgr segment_colour(std::size_t i) {
  // Hues spread by a step prime to 180 (OpenCV's hue range), full value.
  cv::Mat hsv(1, 1, CV_8UC3, cv::Scalar(static_cast<double>((i * 47) % 180), 200, 255)), bgr;
  cv::cvtColor(hsv, bgr, cv::COLOR_HSV2BGR);
  const auto c = bgr.at<cv::Vec3b>(0, 0);
  return {c[0], c[1], c[2]};
}

rt::Status save_bar_chart(const std::filesystem::path& png, const std::string& title,
                          const std::vector<std::string>& groups,
                          const std::vector<std::string>& series,
                          const std::vector<std::vector<double>>& values, double lo) {
  const int w = 900, h = 480, left = 60, right = 20, top = 50, bottom = 70;
  cv::Mat img(h, w, CV_8UC3, cv::Scalar(255, 255, 255));
  const cv::Scalar palette[] = {
      {180, 119, 31}, {14, 127, 255}, {44, 160, 44}, {40, 39, 214}, {189, 103, 148}};
  auto y_of = [&](double v) {
    v = std::clamp(v, lo, 1.0);
    return top + static_cast<int>((1.0 - (v - lo) / (1.0 - lo)) * (h - top - bottom));
  };
  for (int t = 0; t <= 4; ++t) {
    const double v = lo + (1.0 - lo) * t / 4.0;
    cv::line(img, {left, y_of(v)}, {w - right, y_of(v)}, cv::Scalar(220, 220, 220), 1);
    char buf[16];
    std::snprintf(buf, sizeof(buf), "%.2f", v);
    cv::putText(img, buf, {5, y_of(v) + 4}, cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(60, 60, 60),
                1, cv::LINE_AA);
  }
  cv::putText(img, title, {left, 30}, cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(0, 0, 0), 1,
              cv::LINE_AA);
  const int ng = std::max<int>(1, static_cast<int>(groups.size()));
  const int group_w = (w - left - right) / ng;
  const int bar_w = std::max(4, (group_w - 20) / std::max<int>(1, static_cast<int>(series.size())));
  for (int g = 0; g < static_cast<int>(groups.size()); ++g) {
    const int x0 = left + g * group_w + 10;
    for (int s = 0; s < static_cast<int>(series.size()); ++s) {
      const double v = values[static_cast<std::size_t>(s)][static_cast<std::size_t>(g)];
      if (!std::isfinite(v)) continue;
      cv::rectangle(img, {x0 + s * bar_w, y_of(v)}, {x0 + (s + 1) * bar_w - 2, y_of(lo)},
                    palette[s % 5], cv::FILLED);
    }
    cv::putText(img, groups[static_cast<std::size_t>(g)], {x0, h - bottom + 20},
                cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  }
  for (int s = 0; s < static_cast<int>(series.size()); ++s) {
    const cv::Point p(left + 150 * s, h - 20);
    cv::rectangle(img, p + cv::Point(0, -10), p + cv::Point(12, 2), palette[s % 5], cv::FILLED);
    cv::putText(img, series[static_cast<std::size_t>(s)], p + cv::Point(16, 0),
                cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  }
  return write_png(png, img);
}

rt::Status save_confusion_matrix(const std::filesystem::path& png, const std::string& title,
                                 const std::vector<std::string>& names,
                                 const std::vector<std::vector<std::uint64_t>>& counts) {
  constexpr int kCell = 90, kLeft = 120, kTop = 70;
  const int n = static_cast<int>(names.size());
  cv::Mat img(kTop + kCell * n + 40, kLeft + kCell * n + 20, CV_8UC3, cv::Scalar(255, 255, 255));
  cv::putText(img, title, {10, 25}, cv::FONT_HERSHEY_SIMPLEX, 0.6, {0, 0, 0}, 1, cv::LINE_AA);
  cv::putText(img, "rows: truth, columns: predicted", {10, 50}, cv::FONT_HERSHEY_SIMPLEX, 0.45,
              {80, 80, 80}, 1, cv::LINE_AA);
  for (std::size_t i = 0; i < names.size(); ++i) {
    std::uint64_t row = 0;
    for (std::uint64_t v : counts[i]) row += v;
    const int y = kTop + static_cast<int>(i) * kCell;
    cv::putText(img, names[i], {5, y + kCell / 2}, cv::FONT_HERSHEY_SIMPLEX, 0.45, {0, 0, 0}, 1,
                cv::LINE_AA);
    for (std::size_t j = 0; j < names.size(); ++j) {
      const int x = kLeft + static_cast<int>(j) * kCell;
      const double f =
          row == 0 ? 0.0 : static_cast<double>(counts[i][j]) / static_cast<double>(row);
      const auto shade = static_cast<int>(255.0 * (1.0 - f));
      cv::rectangle(img, {x, y}, {x + kCell - 2, y + kCell - 2}, cv::Scalar(255, shade, shade),
                    cv::FILLED);
      cv::putText(img, std::to_string(counts[i][j]), {x + 20, y + kCell / 2},
                  cv::FONT_HERSHEY_SIMPLEX, 0.6,
                  f > 0.5 ? cv::Scalar(255, 255, 255) : cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
      if (i == 0) {
        cv::putText(img, names[j], {x, kTop + kCell * n + 25}, cv::FONT_HERSHEY_SIMPLEX, 0.4,
                    {0, 0, 0}, 1, cv::LINE_AA);
      }
    }
  }
  return write_png(png, img);
}

rt::Status save_side_by_side(const std::filesystem::path& left, const std::filesystem::path& right,
                             const std::filesystem::path& png) {
  const cv::Mat a = cv::imread(left.string()), b = cv::imread(right.string());
  if (a.empty() || b.empty() || a.rows != b.rows) {
    return rt::make_error(png.string() + ": cannot put " + left.string() + " and " +
                          right.string() + " side by side (unreadable, or not the same height)");
  }
  cv::Mat both;
  cv::hconcat(a, b, both);
  return write_png(png, both, {cv::IMWRITE_PNG_COMPRESSION, 9});
}

}  // namespace stac::pictures
