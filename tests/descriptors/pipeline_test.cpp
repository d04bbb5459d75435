// The descriptor pipeline on synthetic segments: layout, hand-computed spin images, invariance
// to yaw and to point order, degenerate segments, and no allocation per segment.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <random>
#include <type_traits>
#include <vector>

#include "perception/descriptors/descriptors.hpp"
#include "rt/testing/alloc_counter.hpp"

namespace stac::descriptors {
namespace {

static_assert(noexcept(std::declval<DescriptorPipeline&>().compute(
    std::declval<const SegmentView&>(), std::declval<Descriptors&>())));

using Cloud = std::vector<float>;  // x, y, z, intensity per point

SegmentView view(const Cloud& c) {
  SegmentView v;
  v.xyzi = c.data();
  v.count = c.size() / 4;
  return v;
}

// An asymmetric "car": a 4.4 x 1.8 x 0.9 m body with a 2 x 1.7 x 0.6 m cab over its rear half,
// points on the surfaces, intensity varying along the body. Rotated by yaw, moved to (x, y, z).
Cloud car(double yaw, double x, double y, double z, unsigned seed = 3) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Cloud c;
  auto add = [&](double px, double py, double pz) {
    const double i = 60.0 + 40.0 * std::sin(2.0 * px) + (pz > 0.9 ? 80.0 : 0.0);
    c.insert(c.end(), {static_cast<float>(x + std::cos(yaw) * px - std::sin(yaw) * py),
                       static_cast<float>(y + std::sin(yaw) * px + std::cos(yaw) * py),
                       static_cast<float>(z + pz), static_cast<float>(i)});
  };
  for (int k = 0; k < 1500; ++k) {  // body sides and top
    const double px = -2.2 + 4.4 * u(rng), pz = 0.9 * u(rng);
    add(px, u(rng) < 0.5 ? -0.9 : 0.9, pz);
    add(px, -0.9 + 1.8 * u(rng), 0.9);
  }
  for (int k = 0; k < 600; ++k) {  // cab over the rear
    add(-2.0 + 2.0 * u(rng), -0.85 + 1.7 * u(rng), 1.5);
    add(-2.0 + 2.0 * u(rng), u(rng) < 0.5 ? -0.85 : 0.85, 0.9 + 0.6 * u(rng));
  }
  return c;
}

double max_abs_diff(std::span<const float> a, std::span<const float> b) {
  double worst = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    worst = std::max(worst, double(std::fabs(a[i] - b[i])));
  return worst;
}

TEST(DescriptorLayout, TwentyNineNamedSpacesTile931Values) {
  const auto& s = spaces();
  std::size_t offset = 0;
  for (const Space& space : s) {
    EXPECT_EQ(space.offset, offset) << space.name;
    offset += space.size;
  }
  EXPECT_EQ(offset, kDimensions);
  EXPECT_EQ(kDimensions, 931u);
  EXPECT_EQ(s[0].name, "bbox_size");
  EXPECT_EQ(s[1].name, "spin_3ppm_10x10");
  EXPECT_EQ(s[2].size, 98u);
  EXPECT_EQ(s[5].name, "hog_front_15x30_u0_v1");
  EXPECT_EQ(s[28].name, "hog_top_30x30_u1_v1");
}

TEST(DescriptorPipeline, InvalidConfigIsRejectedNamingTheKey) {
  DescriptorConfig c;
  c.min_image_px = 20;
  EXPECT_NE(std::string(validate(c)).find("min_image_px"), std::string::npos);
  EXPECT_THROW(DescriptorPipeline{c}, std::invalid_argument);
  c = DescriptorConfig{};
  c.intensity_full_scale = 0;
  EXPECT_THROW(DescriptorPipeline{c}, std::invalid_argument);
}

// Four rings of 8 points, radius 0.5 m, at z = -0.35, -0.15, 0.15, 0.35 about the centroid:
// spin (7 px/m, 14x7): column floor(0.5 * 7) = 3, rows floor((1 - z) * 7) = 9, 8, 5, 4;
// spin (3 px/m, 10x10): column 1, rows floor((5/3 - z) * 3) = 6, 5, 4, 3. Each bin holds 8
// points; whitened: (8 - mean) / std over all bins, the rest -mean / std.
TEST(DescriptorPipeline, SpinImagesOfRingsMatchHandComputedBins) {
  Cloud c;
  for (const double z : {-0.35, -0.15, 0.15, 0.35}) {
    for (int k = 0; k < 8; ++k) {
      const double a = k * M_PI / 4 + 0.1;
      c.insert(c.end(),
               {static_cast<float>(7 + 0.5 * std::cos(a)),
                static_cast<float>(-3 + 0.5 * std::sin(a)), static_cast<float>(z - 1.0), 50.0f});
    }
  }
  DescriptorPipeline pipeline(DescriptorConfig{});
  Descriptors d;
  pipeline.compute(view(c), d);
  ASSERT_EQ(d.status, Status::kOk);
  auto expect_bins = [&](std::size_t space, int cols, std::initializer_list<int> rows, int col) {
    const std::span<const float> img = d.space(space);
    const double n = double(img.size()), mean = 32.0 / n;
    const double var = (4 * (8 - mean) * (8 - mean) + (n - 4) * mean * mean) / n;
    std::vector<double> expected(img.size(), -mean / std::sqrt(var));
    for (const int r : rows) expected[std::size_t(r * cols + col)] = (8 - mean) / std::sqrt(var);
    for (std::size_t i = 0; i < img.size(); ++i) EXPECT_NEAR(img[i], expected[i], 1e-5) << i;
  };
  expect_bins(1, 10, {6, 5, 4, 3}, 1);
  expect_bins(2, 7, {9, 8, 5, 4}, 3);
  EXPECT_NEAR(d.values[0], 1.0, 0.01);  // bbox: the ring's diameter in x and y (about 1 m)
  EXPECT_NEAR(d.values[2], 0.7, 1e-5);  // and its height
}

TEST(DescriptorPipeline, BoxSizeAndViewsOfACarFollowItsShape) {
  DescriptorPipeline pipeline(DescriptorConfig{});
  Descriptors d;
  const Cloud c = car(0.7, 12, -4, -1.2);
  pipeline.compute(view(c), d);
  ASSERT_EQ(d.status, Status::kOk);
  EXPECT_EQ(d.points_used, c.size() / 4);
  // PCA of random surface samples is off the body axis by about 0.01 rad: the width grows by
  // about 4.4 m x 0.01.
  EXPECT_NEAR(d.values[0], 4.4, 0.05);
  EXPECT_NEAR(d.values[1], 1.8, 0.1);
  EXPECT_NEAR(d.values[2], 1.5, 0.01);
  // Views at 15 px/m: side 4.4 x 1.5 m -> 67-68 x 23, height padded to 30; front 28 -> 30.
  const auto side = pipeline.image(DescriptorPipeline::View::kSide);
  EXPECT_GE(side.width, 67u);
  EXPECT_LE(side.width, 68u);
  EXPECT_EQ(side.height, 30u);
  const auto front = pipeline.image(DescriptorPipeline::View::kFront);
  EXPECT_EQ(front.width, 30u);
  for (const float v : d.values) ASSERT_TRUE(std::isfinite(v));
  for (std::size_t k = 5; k < kSpaceCount; ++k) {
    double norm = 0;
    for (const float v : d.space(k)) norm += double(v) * v;
    EXPECT_GT(norm, 0.01) << spaces()[k].name;  // every HOG window sees structure
  }
}

TEST(DescriptorPipeline, DescriptorsOfACarAreInvariantToYaw) {
  DescriptorPipeline pipeline(DescriptorConfig{});
  Descriptors reference, rotated;
  pipeline.compute(view(car(0.0, 10, 3, -1)), reference);
  for (const double yaw : {0.4, 1.3, 2.2, 3.1, -0.8, -2.6}) {
    SCOPED_TRACE(yaw);
    pipeline.compute(view(car(yaw, 10, 3, -1)), rotated);
    EXPECT_NEAR(std::remainder(pipeline.yaw() - yaw, 2 * M_PI), 0.0, 0.02);
    for (std::size_t k = 0; k < kSpaceCount; ++k) {
      // A point within float rounding of a pixel edge may change pixel: a little slack.
      EXPECT_LT(max_abs_diff(reference.space(k), rotated.space(k)), k == 0 ? 1e-4 : 0.05)
          << spaces()[k].name;
    }
  }
}

TEST(DescriptorPipeline, DescriptorsDoNotDependOnPointOrder) {
  const Cloud c = car(0.9, -8, 6, -1.1);
  std::vector<std::uint32_t> order(c.size() / 4);
  std::iota(order.begin(), order.end(), 0u);
  std::mt19937 rng(5);
  std::shuffle(order.begin(), order.end(), rng);
  DescriptorPipeline pipeline(DescriptorConfig{});
  Descriptors a, b;
  pipeline.compute(view(c), a);
  SegmentView shuffled = view(c);
  shuffled.indices = order;
  pipeline.compute(shuffled, b);
  EXPECT_LT(max_abs_diff(a.values, b.values), 1e-3);
}

TEST(DescriptorPipeline, DegenerateSegmentsGiveDefinedOutputs) {
  DescriptorPipeline pipeline(DescriptorConfig{});
  Descriptors d;
  pipeline.compute(SegmentView{}, d);  // no points
  EXPECT_EQ(d.status, Status::kEmpty);
  for (const float v : d.values) EXPECT_EQ(v, 0.0f);

  const float nan = std::nanf("");
  const Cloud bad = {nan, 1, 1, 5, 1, nan, 1, 5, 1, 1, INFINITY, 5, 1, 1, 1, nan};
  pipeline.compute(view(bad), d);
  EXPECT_EQ(d.status, Status::kEmpty);
  EXPECT_EQ(d.points_invalid, 4u);

  const Cloud one = {5, 2, -1, 80};
  pipeline.compute(view(one), d);
  EXPECT_EQ(d.status, Status::kOk);
  for (const float v : d.values) ASSERT_TRUE(std::isfinite(v));
  EXPECT_EQ(d.values[0], 0.0f);
  EXPECT_EQ(pipeline.image(DescriptorPipeline::View::kTop).width, 30u);

  Cloud same;
  for (int k = 0; k < 50; ++k) same.insert(same.end(), {5, 2, -1, 80});
  same.insert(same.end(), {nan, 0, 0, 0});
  pipeline.compute(view(same), d);
  EXPECT_EQ(d.status, Status::kOk);
  EXPECT_EQ(d.points_used, 50u);
  EXPECT_EQ(d.points_invalid, 1u);
  for (const float v : d.values) ASSERT_TRUE(std::isfinite(v));
}

TEST(DescriptorPipeline, CapacitiesAreCountedNotOverrun) {
  DescriptorConfig config;
  config.max_points = 100;
  config.max_image_px = 40;
  DescriptorPipeline pipeline(config);
  Descriptors d;
  const Cloud c = car(0.2, 5, 5, -1);  // 4.4 m long: 67 px > 40
  pipeline.compute(view(c), d);
  EXPECT_EQ(d.points_used, 100u);
  EXPECT_EQ(d.points_over_capacity, c.size() / 4 - 100);
  EXPECT_GT(d.pixels_cropped, 0u);
  EXPECT_EQ(pipeline.image(DescriptorPipeline::View::kSide).width, 40u);
  for (const float v : d.values) ASSERT_TRUE(std::isfinite(v));
}

// A segment over max_points is read at evenly spaced positions (not its first max_points, which
// are one end of a scan-ordered segment): each point twice in a row, capped at the number of
// distinct points, reads each once and describes exactly the distinct points (spin counts are
// halved, which whitening undoes up to rounding).
TEST(DescriptorPipeline, ASegmentOverMaxPointsIsDescribedFromEvenlySpacedPoints) {
  const Cloud distinct = car(0.3, 8, -2, -1);
  const std::size_t n = distinct.size() / 4;
  Cloud doubled;
  for (std::size_t i = 0; i < n; ++i) {
    for (int twice = 0; twice < 2; ++twice)
      doubled.insert(doubled.end(), distinct.begin() + 4 * i, distinct.begin() + 4 * i + 4);
  }
  DescriptorConfig capped;
  capped.max_points = n;
  DescriptorPipeline all(DescriptorConfig{}), sampled(capped);
  Descriptors expected, d;
  all.compute(view(distinct), expected);
  sampled.compute(view(doubled), d);
  EXPECT_EQ(d.points_used, n);
  EXPECT_EQ(d.points_over_capacity, n);
  for (std::size_t k = 0; k < kDimensions; ++k)
    EXPECT_NEAR(d.values[k], expected.values[k], 1e-4f) << k;
  // The first n points alone are the car's first half: other descriptors.
  Cloud first_half(doubled.begin(), doubled.begin() + static_cast<std::ptrdiff_t>(4 * n));
  Descriptors half;
  all.compute(view(first_half), half);
  EXPECT_NE(half.values, expected.values);
}

// Points on the faces of an axis-aligned box (sx x sy x sz m) at (x, y, z), intensity varying
// along x; a regular pattern of "windows" is left out so that the views have structure.
Cloud box(double sx, double sy, double sz, double x, double y, double z, int points,
          unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Cloud c;
  while (c.size() / 4 < static_cast<std::size_t>(points)) {
    double px = sx * u(rng), py = sy * u(rng), pz = sz * u(rng);
    switch (rng() % 3) {
      case 0:
        py = u(rng) < 0.5 ? 0.0 : sy;
        break;
      case 1:
        px = u(rng) < 0.5 ? 0.0 : sx;
        break;
      default:
        pz = sz;
        break;
    }
    if (std::fmod(px, 1.3) < 0.2 && pz > 0.5 * sz) continue;  // "windows"
    c.insert(c.end(),
             {static_cast<float>(x + px), static_cast<float>(y + py), static_cast<float>(z + pz),
              static_cast<float>(40.0 + 30.0 * std::sin(px) + 20.0 * (pz > 1.0))});
  }
  return c;
}

// FNV-1a of every output bit: values, status and counters.
std::uint64_t fingerprint(const Descriptors& d) {
  std::uint64_t h = 1469598103934665603ull;
  auto mix = [&h](const void* p, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) {
      h ^= static_cast<const unsigned char*>(p)[i];
      h *= 1099511628211ull;
    }
  };
  mix(d.values.data(), sizeof(float) * d.values.size());
  mix(&d.status, sizeof(d.status));
  mix(&d.points_used, sizeof(d.points_used));
  mix(&d.points_invalid, sizeof(d.points_invalid));
  mix(&d.points_over_capacity, sizeof(d.points_over_capacity));
  mix(&d.pixels_cropped, sizeof(d.pixels_cropped));
  return h;
}

// The views are made, smoothed and differentiated only near the HOG windows (and near the
// points); the values must be those of making every view whole. The fingerprints were taken
// from the whole-view implementation (df60c54) on the same segments: small views whose windows
// overlap, views several windows long, views cropped at the capacity, windows with no point.
// A change meant to move descriptor values must update them (and retrain the model).
TEST(DescriptorPipeline, ViewsMadeOnlyNearTheWindowsGiveTheWholeViewsValues) {
  struct Case {
    const char* name;
    Cloud cloud;
    std::uint64_t expected;
  };
  Cloud far_apart = box(0.4, 0.4, 1.7, 4, 4, -1, 300, 11);  // two poles 9 m apart
  const Cloud other = box(0.3, 0.3, 1.2, 4 + 9, 4.5, -1, 200, 12);
  far_apart.insert(far_apart.end(), other.begin(), other.end());
  std::vector<Case> cases;
  cases.push_back({"car", car(0.7, 12, -4, -1.2), 0xfc7f0d1fd7520b48ull});
  cases.push_back({"pole", box(0.2, 0.2, 2.5, 3, 8, -1.5, 120, 1), 0xe8e53df15e71e181ull});
  cases.push_back({"bus", box(12.0, 2.5, 3.0, -20, 5, -1.6, 6000, 2), 0x2be70a340f6fa295ull});
  cases.push_back({"wall", box(40.0, 0.3, 4.0, -10, -15, -1.6, 20000, 3), 0x2c0daf8684831616ull});
  cases.push_back({"far apart", far_apart, 0xfbe1f9783530c2b0ull});
  cases.push_back({"one point", Cloud{5, 2, -1, 80}, 0x9c944dbc72d42cb9ull});
  DescriptorPipeline pipeline(DescriptorConfig{});
  Descriptors d;
  for (const Case& c : cases) {
    pipeline.compute(view(c.cloud), d);
    EXPECT_EQ(fingerprint(d), c.expected) << c.name << ": 0x" << std::hex << fingerprint(d);
  }
  // Cropped: a small capacity.
  DescriptorConfig small;
  small.max_image_px = 64;
  DescriptorPipeline cropped(small);
  cropped.compute(view(cases[3].cloud), d);
  EXPECT_GT(d.pixels_cropped, 0u);
  EXPECT_EQ(fingerprint(d), 0xa678e5c6c49128aeull)
      << "cropped wall: 0x" << std::hex << fingerprint(d);
}

TEST(DescriptorPipeline, ComputeAllocatesNothing) {
  DescriptorPipeline pipeline(DescriptorConfig{});
  Descriptors d;
  const Cloud a = car(0.3, 10, 2, -1), b = car(2.0, -6, 9, -1, 9);
  const float one[4] = {1, 2, 3, 4};
  SegmentView single;
  single.xyzi = one;
  single.count = 1;
  pipeline.compute(view(a), d);  // warm-up
  rt::testing::AllocationCounter counter;
  pipeline.compute(view(a), d);
  pipeline.compute(view(b), d);
  pipeline.compute(single, d);
  pipeline.compute(SegmentView{}, d);
  counter.stop();
  EXPECT_EQ(counter.allocations(), 0u);
}

}  // namespace
}  // namespace stac::descriptors
