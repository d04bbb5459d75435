// The descriptors' own floor and atan2 (perception/descriptors/fast_math.hpp) against libm:
// floor_exact equals std::floor bit for bit, floor_index equals it as an int in range, angle_of is
// within the documented 1.2e-5 rad of std::atan2 mapped to [0, 2 pi), including the axes, the
// diagonals and signed zeros.
#include "perception/descriptors/fast_math.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

namespace stac::descriptors {
namespace {

std::uint32_t bits(float v) {
  std::uint32_t b;
  std::memcpy(&b, &v, sizeof(b));
  return b;
}

TEST(FastMath, FloorExactIsStdFloorBitForBit) {
  std::vector<float> values = {0.0f,
                               -0.0f,
                               0.5f,
                               -0.5f,
                               1.0f,
                               -1.0f,
                               2.9999998f,
                               -2.9999998f,
                               1e-30f,
                               -1e-30f,
                               8388607.5f,
                               -8388607.5f,
                               8388609.0f,
                               2147483520.0f,
                               -2147483648.0f,
                               2147483648.0f,
                               1e20f,
                               -1e20f,
                               std::numeric_limits<float>::infinity(),
                               -std::numeric_limits<float>::infinity()};
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> wide(-1e4f, 1e4f), narrow(-3.0f, 3.0f);
  for (int i = 0; i < 200000; ++i) values.push_back(i % 2 ? wide(rng) : narrow(rng));
  for (const float v : values) {
    EXPECT_EQ(bits(floor_exact(v)), bits(std::floor(v))) << v;
  }
  EXPECT_TRUE(std::isnan(floor_exact(std::numeric_limits<float>::quiet_NaN())));
}

TEST(FastMath, FloorIndexIsStdFloorInRangeAndOutOfRangeBeyondIt) {
  std::vector<float> values = {0.0f,       -0.0f,         0.5f,           -0.5f,
                               1.0f,       -1.0f,         2.9999998f,     -2.9999998f,
                               1e-30f,     -1e-30f,       8388607.5f,     -8388607.5f,
                               8388609.0f, 2147483520.0f, -2147483648.0f, -2147483520.0f};
  std::mt19937 rng(8);
  std::uniform_real_distribution<float> wide(-1e4f, 1e4f), narrow(-3.0f, 3.0f);
  for (int i = 0; i < 200000; ++i) values.push_back(i % 2 ? wide(rng) : narrow(rng));
  for (const float v : values) {
    EXPECT_EQ(floor_index(v), static_cast<int>(std::floor(v))) << v;
  }
  const float inf = std::numeric_limits<float>::infinity();
  for (const float v : {2147483648.0f, 1e20f, inf}) EXPECT_EQ(floor_index(v), 2147483520) << v;
  for (const float v : {-2147483904.0f, -1e20f, -inf, std::numeric_limits<float>::quiet_NaN()}) {
    EXPECT_EQ(floor_index(v), std::numeric_limits<int>::min()) << v;
  }
}

TEST(FastMath, AngleOfIsAtan2WithinTheStatedErrorOnAllOctants) {
  const auto reference = [](float y, float x) {
    double a = std::atan2(static_cast<double>(y), static_cast<double>(x));
    if (a < 0) a += 2 * M_PI;
    return a;
  };
  // Distance on the circle: an angle just under 2 pi and one at 0 are neighbours.
  const auto error = [](double a, double b) {
    const double d = std::fabs(a - b);
    return std::min(d, 2 * M_PI - d);
  };
  double worst = 0;
  for (int k = 0; k < 3600; ++k) {  // every 0.1 degree, at radii from tiny to large
    const double t = k * M_PI / 1800;
    for (const double r : {1e-6, 0.3, 1.0, 255.0, 1e5}) {
      const auto x = static_cast<float>(r * std::cos(t)), y = static_cast<float>(r * std::sin(t));
      if (x == 0 && y == 0) continue;
      const float a = angle_of(y, x);
      ASSERT_GE(a, 0.0f) << x << " " << y;
      ASSERT_LE(a, 2 * kPi) << x << " " << y;
      worst = std::max(worst, error(a, reference(y, x)));
    }
  }
  EXPECT_LT(worst, 1.2e-5);
  // Axes and diagonals, and the signed zeros of an image gradient.
  EXPECT_NEAR(angle_of(0.0f, 1.0f), 0.0, 1e-6);
  EXPECT_NEAR(angle_of(1.0f, 0.0f), M_PI / 2, 1e-5);
  EXPECT_NEAR(angle_of(0.0f, -1.0f), M_PI, 1e-5);
  EXPECT_NEAR(angle_of(-0.0f, -1.0f), M_PI, 1e-5);  // atan2 gives -pi, i.e. pi after the wrap
  EXPECT_NEAR(angle_of(-1.0f, 0.0f), 3 * M_PI / 2, 1e-5);
  EXPECT_NEAR(angle_of(1.0f, 1.0f), M_PI / 4, 1.2e-5);  // the largest error: on the diagonals
  EXPECT_NEAR(angle_of(-1.0f, -1.0f), 5 * M_PI / 4, 1.2e-5);
}

}  // namespace
}  // namespace stac::descriptors
