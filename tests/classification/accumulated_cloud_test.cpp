// The holistic descriptor: a track's motion statistics and box, and the bounded accumulated cloud
// (centring, reservoir sampling, determinism, no allocation) whose descriptors it carries.
#include "perception/classification/accumulated_cloud.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "perception/classification/holistic.hpp"
#include "rt/testing/alloc_counter.hpp"

namespace stac::classification {
namespace {

static_assert(noexcept(std::declval<AccumulatedCloud&>().add_segment(
    std::declval<const descriptors::SegmentView&>())));

// A 1 x 0.5 x 1.7 m box of points at (x, y), intensity = `tag`.
std::vector<float> box_segment(float x, float y, float tag, std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-0.5f, 0.5f);
  std::vector<float> c;
  for (std::size_t i = 0; i < n; ++i)
    c.insert(c.end(), {x + u(rng), y + 0.5f * u(rng), 1.7f * (u(rng) + 0.5f), tag});
  return c;
}

descriptors::SegmentView view(const std::vector<float>& c) {
  descriptors::SegmentView v;
  v.xyzi = c.data();
  v.count = c.size() / 4;
  return v;
}

TEST(AccumulatedCloud, SegmentsAreCentredInXYAndKeepZ) {
  AccumulatedCloud cloud(1000);
  const auto a = box_segment(10.0f, 20.0f, 1.0f, 200, 1),
             b = box_segment(12.0f, 21.0f, 2.0f, 200, 2);
  cloud.add_segment(view(a));
  cloud.add_segment(view(b));
  ASSERT_EQ(cloud.size(), 400u);
  double sx = 0, sy = 0, zmin = 1e9;
  float p[4];
  for (std::size_t k = 0; k < cloud.size(); ++k) {
    cloud.view().read(k, p);
    sx += p[0];
    sy += p[1];
    zmin = std::min(zmin, double(p[2]));
  }
  EXPECT_NEAR(sx / 400, 0.0, 1e-4);
  EXPECT_NEAR(sy / 400, 0.0, 1e-4);
  EXPECT_GE(zmin, 0.0);  // z is not moved
}

TEST(AccumulatedCloud, KeepsAtMostCapacityWithEveryFrameFairlyRepresented) {
  AccumulatedCloud cloud(1000, 7);
  for (int f = 0; f < 10; ++f)
    cloud.add_segment(view(box_segment(float(f), 0.0f, float(f), 1000, unsigned(f))));
  EXPECT_EQ(cloud.size(), 1000u);
  EXPECT_EQ(cloud.points_seen(), 10000u);
  int per_frame[10] = {};
  float p[4];
  for (std::size_t k = 0; k < cloud.size(); ++k) {
    cloud.view().read(k, p);
    ++per_frame[static_cast<int>(p[3])];
  }
  for (int f = 0; f < 10; ++f) {  // 100 expected, binomial sd about 9.5
    EXPECT_GT(per_frame[f], 60) << "frame " << f;
    EXPECT_LT(per_frame[f], 140) << "frame " << f;
  }
}

TEST(AccumulatedCloud, SameSeedSamePointsAndInvalidPointsSkipped) {
  AccumulatedCloud a(300, 5), b(300, 5);
  auto seg = box_segment(3.0f, 4.0f, 1.0f, 500, 3);
  seg[4 * 10] = std::nanf("");  // point 10's x
  for (AccumulatedCloud* c : {&a, &b}) {
    c->add_segment(view(seg));
    c->add_segment(view(seg));
  }
  EXPECT_EQ(a.points_seen(), 998u);
  float p[4], q[4];
  for (std::size_t k = 0; k < a.size(); ++k) {
    a.view().read(k, p);
    b.view().read(k, q);
    ASSERT_EQ(std::memcmp(p, q, sizeof(p)), 0) << "point " << k;
  }
  a.clear();
  EXPECT_EQ(a.size(), 0u);
}

TEST(AccumulatedCloud, AddingSegmentsAllocatesNothing) {
  AccumulatedCloud cloud(2000);
  const auto seg = box_segment(1.0f, 2.0f, 1.0f, 800, 4);
  cloud.add_segment(view(seg));
  rt::testing::AllocationCounter counter;
  for (int f = 0; f < 20; ++f) cloud.add_segment(view(seg));
  counter.stop();
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_EQ(cloud.size(), 2000u);
}

tracking::Track moving_track() {
  tracking::Track track;
  track.length = 4.5f;
  track.width = 1.8f;
  track.height = 1.5f;
  for (int i = 0; i < 20; ++i)  // 2 m/s along x at 10 Hz
    track.features.add_segment(Eigen::Vector3f(0.2f * float(i), 0.0f, 0.0f),
                               std::int64_t{i} * 100'000'000, 0.5);
  return track;
}

TEST(HolisticDescriptor, MotionStatisticsAndBoxOfATrack) {
  HolisticDescriptor d{};
  holistic_descriptor(moving_track(), nullptr, d);
  EXPECT_NEAR(d[0], 2.0f, 1e-3f);  // max speed
  EXPECT_NEAR(d[1], 2.0f, 1e-3f);  // mean speed
  EXPECT_NEAR(d[2], 0.0f, 1e-2f);  // max accel
  EXPECT_NEAR(d[3], 0.0f, 1e-2f);  // mean accel
  EXPECT_NEAR(d[4], 0.0f, 1e-3f);  // max angular velocity
  EXPECT_EQ(d[5], 20.0f);
  EXPECT_EQ(d[6], 4.5f);
  EXPECT_EQ(d[7], 1.8f);
  EXPECT_EQ(d[8], 1.5f);
  for (std::size_t e = kHolisticMotionDimensions; e < kHolisticDimensions; ++e)
    ASSERT_TRUE(std::isnan(d[e])) << "no accumulated cloud: element " << e << " is no evidence";
}

TEST(HolisticDescriptor, CarriesTheAccumulatedCloudsDescriptors) {
  AccumulatedCloud cloud(4000);
  for (int f = 0; f < 5; ++f)
    cloud.add_segment(view(box_segment(float(f), 0.0f, 100.0f, 600, unsigned(f))));
  descriptors::DescriptorPipeline pipeline(descriptors::DescriptorConfig{});
  descriptors::Descriptors acc;
  pipeline.compute(cloud.view(), acc);
  ASSERT_EQ(acc.status, descriptors::Status::kOk);
  HolisticDescriptor d{};
  holistic_descriptor(moving_track(), &acc, d);
  for (std::size_t e = 0; e < descriptors::kDimensions; ++e)
    ASSERT_EQ(d[kHolisticMotionDimensions + e], acc.values[e]) << e;
  EXPECT_NEAR(d[kHolisticMotionDimensions + 2], 1.7f, 0.05f);  // box height of the cloud
  const Layout l = holistic_layout();
  EXPECT_EQ(l[kHolisticMotionDimensions].name,
            "accumulated." + std::string(descriptors::spaces()[0].name));
}

}  // namespace
}  // namespace stac::classification
