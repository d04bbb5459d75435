// Line charts (pictures/chart.hpp): the legend sits in the corner of the plot that the lines
// cross least, on white, so that no line runs under its text.
#include "pictures/chart.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "pictures/birds_eye.hpp"

namespace stac::pictures {
namespace {

// The chart's frame (chart.cpp): 70 px left, 40 px top, 50 px bottom; 800 x 420.
constexpr int kLeft = 70, kTop = 40, kPlotH = 420 - 40 - 50, kPlotW = 800 - 70 - 20;

cv::Vec3b pixel_of(const Chart& chart, int x, int y) {
  const auto png = std::filesystem::temp_directory_path() /
                   ("stac_chart_test_" + std::to_string(::getpid()) + ".png");
  EXPECT_TRUE(save_chart(chart, png));
  const cv::Mat img = cv::imread(png.string());
  std::filesystem::remove(png);
  if (img.empty()) return {};
  return img.at<cv::Vec3b>(y, x);
}

const cv::Vec3b kFirstColour(200, 120, 40);  // BGR of the first series

TEST(Chart, TheLegendGoesWhereNoLineRuns) {
  Chart c;
  c.series.push_back({"a", {0.0, 10.0}, {0.5, 0.5}});  // mid-height: every corner is free
  // Free corners: top right, the first choice; the swatch of series 0 at 6 px in, 13 px down.
  const int legend_w = 40 + 9;
  EXPECT_EQ(pixel_of(c, kLeft + kPlotW - legend_w + 6 + 12, kTop + 13), kFirstColour);

  // A line along the top (0.95 of an axis up to 1.0, ticks of 0.2) and one low on the right
  // half leave the bottom-left corner.
  c.series = {{"top", {0.0, 10.0}, {0.95, 0.95}}, {"low", {5.0, 10.0}, {0.05, 0.05}}};
  const int legend_h = 8 + 18 * 2;
  const int box_y = kTop + kPlotH - legend_h;
  EXPECT_EQ(pixel_of(c, kLeft + 6 + 12, box_y + 13), kFirstColour);
  // Nothing of the legend top right, where the line runs.
  const int wide = 40 + 9 * 3;
  EXPECT_NE(pixel_of(c, kLeft + kPlotW - wide + 6 + 12, kTop + 13), kFirstColour);
}

TEST(Chart, AFileThatCannotBeWrittenIsNamed) {
  Chart c;
  c.series.push_back({"a", {0.0, 1.0}, {0.0, 1.0}});
  const auto r = save_chart(c, "/nonexistent/folder/chart.png");
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("/nonexistent/folder/chart.png"), std::string::npos);
}

// A point whose coordinates are NaN, infinite or far off the picture is left out (issue 47: a KITTI
// scan with a point of NaN x, y and z crashed stac sim-compare's picture); one on it is drawn.
TEST(BirdsEye, NonFiniteAndFarPointsAreLeftOutAndThePictureIsWritten) {
  BirdsEyeOptions o;
  o.size_px = 200;
  o.range_m = 10.0;
  BirdsEye view(o);
  const float nan = std::nanf(""), inf = std::numeric_limits<float>::infinity();
  view.add_point(nan, nan, nan);
  view.add_point(inf, -inf, 0.0f);
  view.add_point(1e30f, 0.0f, 1e30f);
  view.add_point(0.0f, 3e9f, 0.0f);
  view.add_point(5.0f, 0.0f, nan);  // on the picture: drawn in the bottom colour
  const auto png = std::filesystem::temp_directory_path() /
                   ("stac_birds_eye_test_" + std::to_string(::getpid()) + ".png");
  ASSERT_TRUE(view.save(png));
  const cv::Mat img = cv::imread(png.string());
  std::filesystem::remove(png);
  ASSERT_FALSE(img.empty());
  EXPECT_EQ(img.at<cv::Vec3b>(50, 100), cv::Vec3b(84, 1, 68));  // x 5 m forward: 50 px up
}

}  // namespace
}  // namespace stac::pictures
