#include "pictures/birds_eye.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "pictures/png.hpp"

namespace stac::pictures {
namespace {

// A perceptual blue-to-yellow ramp (viridis-like) for t in [0, 1] (NaN: the bottom colour).
Bgr ramp(double t) {
  static const double stops[5][3] = {
      {68, 1, 84}, {59, 82, 139}, {33, 145, 140}, {94, 201, 98}, {253, 231, 37}};  // RGB
  if (!(t >= 0.0)) t = 0.0;  // NaN would index the stops at INT_MIN
  t = std::min(t, 1.0) * 4.0;
  const int i = std::min(static_cast<int>(t), 3);
  const double f = t - i;
  auto mix = [&](int c) {
    return static_cast<unsigned char>(stops[i][c] + f * (stops[i + 1][c] - stops[i][c]));
  };
  return {mix(2), mix(1), mix(0)};  // BGR
}

cv::Scalar scalar(Bgr c) {
  return {static_cast<double>(c.b), static_cast<double>(c.g), static_cast<double>(c.r)};
}

// The picture's pixels as an OpenCV image (no copy).
cv::Mat canvas(std::vector<std::uint8_t>& image, int size_px) {
  return {size_px, size_px, CV_8UC3, image.data()};
}

// A point (m) -> its pixel: x forward is up in the picture, y left is left.
cv::Point pixel(const BirdsEyeOptions& o, double px_per_m, double x, double y) noexcept {
  return {static_cast<int>(std::lround(o.size_px / 2.0 - y * px_per_m)),
          static_cast<int>(std::lround(o.size_px / 2.0 - x * px_per_m))};
}

}  // namespace

BirdsEye::BirdsEye(const BirdsEyeOptions& options)
    : options_(options),
      px_per_m_(options.size_px / (2.0 * options.range_m)),
      image_(
          static_cast<std::size_t>(options.size_px) * static_cast<std::size_t>(options.size_px) * 3,
          20) {
  cv::Mat img = canvas(image_, options.size_px);
  const cv::Point centre(options.size_px / 2, options.size_px / 2);
  for (int r = 10; r <= static_cast<int>(options.range_m * 1.5); r += 10) {
    cv::circle(img, centre, static_cast<int>(r * px_per_m_), cv::Scalar(60, 60, 60), 1,
               cv::LINE_AA);
    cv::putText(img, std::to_string(r) + " m",
                centre + cv::Point(4, -static_cast<int>(r * px_per_m_) + 12),
                cv::FONT_HERSHEY_SIMPLEX, 0.35, cv::Scalar(110, 110, 110), 1, cv::LINE_AA);
  }
}

void BirdsEye::add_point(float x, float y, float z) noexcept {
  add_point(x, y, ramp((z - options_.z_min_m) / (options_.z_max_m - options_.z_min_m)));
}

void BirdsEye::add_point(float x, float y, Bgr colour) noexcept {
  // Off the picture (NaN and infinities too) before any conversion to int.
  const double limit = options_.size_px / (2.0 * px_per_m_);
  if (!(std::abs(x) <= limit && std::abs(y) <= limit)) return;
  const cv::Point p = pixel(options_, px_per_m_, x, y);
  if (p.x < 0 || p.y < 0 || p.x >= options_.size_px || p.y >= options_.size_px) return;
  const std::size_t at =
      (static_cast<std::size_t>(p.y) * static_cast<std::size_t>(options_.size_px) +
       static_cast<std::size_t>(p.x)) *
      3;
  image_[at] = colour.b;
  image_[at + 1] = colour.g;
  image_[at + 2] = colour.r;
}

void BirdsEye::add_path(std::span<const PointM> points_m, Bgr colour, int thickness_px) {
  cv::Mat img = canvas(image_, options_.size_px);
  for (std::size_t i = 1; i < points_m.size(); ++i) {
    cv::line(img, pixel(options_, px_per_m_, points_m[i - 1].x, points_m[i - 1].y),
             pixel(options_, px_per_m_, points_m[i].x, points_m[i].y), scalar(colour), thickness_px,
             cv::LINE_AA);
  }
}

void BirdsEye::add_label(float x, float y, const std::string& text, Bgr colour) {
  cv::Mat img = canvas(image_, options_.size_px);
  cv::putText(img, text, pixel(options_, px_per_m_, x, y) + cv::Point(4, -4),
              cv::FONT_HERSHEY_SIMPLEX, 0.35, scalar(colour), 1, cv::LINE_AA);
}

void BirdsEye::add_box(float cx, float cy, float length, float width, float yaw, Bgr colour) {
  const double c = std::cos(yaw), s = std::sin(yaw);
  const double corners[4][2] = {{length / 2.0, width / 2.0},
                                {-length / 2.0, width / 2.0},
                                {-length / 2.0, -width / 2.0},
                                {length / 2.0, -width / 2.0}};
  cv::Point px[4];
  for (int i = 0; i < 4; ++i) {
    const double x = cx + c * corners[i][0] - s * corners[i][1];
    const double y = cy + s * corners[i][0] + c * corners[i][1];
    px[i] = pixel(options_, px_per_m_, x, y);
  }
  cv::Mat img = canvas(image_, options_.size_px);
  for (int i = 0; i < 4; ++i) cv::line(img, px[i], px[(i + 1) % 4], scalar(colour), 1, cv::LINE_AA);
}

void BirdsEye::add_legend(const std::string& line) {
  cv::Mat img = canvas(image_, options_.size_px);
  cv::putText(img, line, cv::Point(10, 20 + 18 * legend_lines_++), cv::FONT_HERSHEY_SIMPLEX, 0.5,
              cv::Scalar(230, 230, 230), 1, cv::LINE_AA);
}

rt::Status BirdsEye::save(const std::filesystem::path& png) const {
  std::vector<std::uint8_t> copy = image_;
  cv::Mat out = canvas(copy, options_.size_px);
  if (options_.height_bar) {  // height colour bar, bottom left
    const int bar_w = 200, bar_h = 10, x0 = 10, y0 = options_.size_px - 30;
    for (int i = 0; i < bar_w; ++i) {
      cv::line(out, {x0 + i, y0}, {x0 + i, y0 + bar_h}, scalar(ramp(i / (bar_w - 1.0))), 1);
    }
    char label[64];
    std::snprintf(label, sizeof(label), "z %.1f m .. %.1f m", options_.z_min_m, options_.z_max_m);
    cv::putText(out, label, {x0, y0 - 5}, cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(200, 200, 200),
                1, cv::LINE_AA);
  }
  return write_png(png, out);
}

}  // namespace stac::pictures
