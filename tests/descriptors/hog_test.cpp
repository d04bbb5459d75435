// Our allocation-free HOG against OpenCV's cv::HOGDescriptor (the reference, test only) on the
// same 8-bit images with the same parameters: window = block (15x30, 30x30, 15x15), block stride
// 10x10, cell 5x5, 6 unsigned bins, derivAperture 1, default winSigma (Gaussian block weighting,
// which we implement too), L2-Hys 0.2, no gamma correction, no padding, explicit locations.
// Compared: the final normalised descriptors, element by element. The only expected difference
// is OpenCV's polynomial atan approximation in cartToPolar (about 0.01 degree).
#include "perception/descriptors/hog.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>
#include <opencv2/objdetect.hpp>
#include <random>
#include <vector>

namespace stac::descriptors {
namespace {

// A smooth random scene of blobs and edges, like a smoothed intensity view.
cv::Mat scene(int width, int height, unsigned seed) {
  cv::Mat img(height, width, CV_8UC1, cv::Scalar(0));
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> x(0, width - 1), y(0, height - 1), v(40, 255), r(2, 9);
  for (int k = 0; k < 12; ++k) cv::circle(img, {x(rng), y(rng)}, r(rng), cv::Scalar(v(rng)), -1);
  for (int k = 0; k < 4; ++k) {
    cv::rectangle(img, {x(rng), y(rng)}, {x(rng), y(rng)}, cv::Scalar(v(rng)), -1);
  }
  cv::GaussianBlur(img, img, cv::Size(3, 3), 0);
  return img;
}

void expect_matches_opencv(const cv::Mat& img, const HogShape& shape) {
  cv::HOGDescriptor reference(cv::Size(shape.width, shape.height),
                              cv::Size(shape.width, shape.height), cv::Size(10, 10),
                              cv::Size(shape.cell, shape.cell), shape.bins, 1, -1,
                              cv::HOGDescriptor::L2Hys, shape.l2hys_clip, false);
  ASSERT_EQ(reference.getDescriptorSize(), shape.size());
  std::vector<cv::Point> locations;
  for (int y = 0; y + shape.height <= img.rows; y += 7) {
    for (int x = 0; x + shape.width <= img.cols; x += 6) locations.emplace_back(x, y);
  }
  locations.emplace_back(img.cols - shape.width, img.rows - shape.height);  // both far edges
  std::vector<float> expected;
  reference.compute(img, expected, cv::Size(), cv::Size(), locations);
  ASSERT_EQ(expected.size(), locations.size() * shape.size());

  std::vector<float> pixels(img.begin<std::uint8_t>(), img.end<std::uint8_t>());
  GradientCache gradients(pixels.size(), static_cast<std::size_t>(img.rows), shape.bins);
  gradients.reset(pixels.data(), img.cols, img.rows);
  const HogWindow window(shape);
  std::vector<float> ours(shape.size());
  double worst = 0.0;
  std::size_t textured = 0;
  for (std::size_t k = 0; k < locations.size(); ++k) {
    window.compute(gradients, locations[k].x, locations[k].y, ours.data());
    double norm = 0.0;
    for (std::size_t i = 0; i < ours.size(); ++i) {
      const float e = expected[k * shape.size() + i];
      worst = std::max(worst, static_cast<double>(std::fabs(ours[i] - e)));
      norm += static_cast<double>(ours[i]) * ours[i];
    }
    textured += norm > 0.5 ? 1 : 0;  // normalised: unit-ish norm unless the window is flat
  }
  EXPECT_GE(textured * 10, locations.size() * 8) << "the scene must exercise the histograms";
  std::printf("%dx%d: %zu windows, worst |ours - OpenCV| = %.2e\n", shape.width, shape.height,
              locations.size(), worst);
  EXPECT_LT(worst, 1e-3) << shape.width << "x" << shape.height << " over " << locations.size()
                         << " windows";
}

TEST(Hog, MatchesOpenCvHogDescriptorOnTheThesisWindows) {
  for (unsigned seed = 1; seed <= 3; ++seed) {
    const cv::Mat img = scene(64, 48, seed);
    expect_matches_opencv(img, {15, 30, 5, 6, 0.2f});
    expect_matches_opencv(img, {30, 30, 5, 6, 0.2f});
    expect_matches_opencv(img, {15, 15, 5, 6, 0.2f});
  }
}

TEST(Hog, WindowFillingTheWholeImageMatchesOpenCv) {
  expect_matches_opencv(scene(30, 30, 7), {30, 30, 5, 6, 0.2f});  // borders reflect-101
}

TEST(Hog, FlatImageGivesZeroDescriptor) {
  std::vector<float> pixels(40 * 40, 128.0f);
  GradientCache gradients(pixels.size(), 40, 6);
  gradients.reset(pixels.data(), 40, 40);
  const HogWindow window({30, 30, 5, 6, 0.2f});
  std::vector<float> out(window.shape().size(), 1.0f);
  window.compute(gradients, 5, 5, out.data());
  for (const float v : out) EXPECT_EQ(v, 0.0f);
}

TEST(Hog, InvalidShapeIsRejectedAtConstruction) {
  EXPECT_THROW(HogWindow({16, 30, 5, 6, 0.2f}), std::invalid_argument);
  EXPECT_THROW(HogWindow({15, 30, 5, 0, 0.2f}), std::invalid_argument);
}

}  // namespace
}  // namespace stac::descriptors
