// Descriptors of every segment the Segmenter finds in real KITTI scans (object frame 000001 with
// its labeled truck, car and cyclist, and odometry scan 000000): finite values, sizes that
// agree with the segments' boxes, no allocation.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include "perception/descriptors/descriptors.hpp"
#include "perception/segmentation/segmenter.hpp"
#include "rt/testing/alloc_counter.hpp"
#include "shared_data.hpp"

namespace stac::descriptors {
namespace {

void check_scan(const std::string& relative) {
  SCOPED_TRACE(relative);
  const auto cloud = testing::read_kitti_bin(relative);
  // The principal-axis box (box_fit_points 0): the definition of the bbox_size space, so the two
  // can be compared below (the default L-shape fit turns boxes of long segments).
  segmentation::SegmenterConfig by_axis;
  by_axis.box_fit_points = 0;
  segmentation::Segmenter segmenter(by_axis);
  auto segments = segmenter.make_segments();
  segmenter.segment({cloud.data(), cloud.size() / 4, 16}, segments);
  ASSERT_GE(segments.segments.size(), 20u);
  DescriptorConfig config;
  config.intensity_full_scale = 1.0;  // KITTI reflectance is 0..1
  DescriptorPipeline pipeline(config);
  Descriptors d;
  SegmentView view;
  view.xyzi = cloud.data();
  view.stride_bytes = 16;
  view.indices = segments.indices(segments.segments[0]);
  pipeline.compute(view, d);                               // warm-up
  std::vector<Descriptors> all(segments.segments.size());  // checked after counting
  rt::testing::AllocationCounter counter;
  for (std::size_t k = 0; k < all.size(); ++k) {
    view.indices = segments.indices(segments.segments[k]);
    pipeline.compute(view, all[k]);
  }
  counter.stop();
  EXPECT_EQ(counter.allocations(), 0u);
  std::size_t checked = 0;
  for (std::size_t k = 0; k < all.size(); ++k) {
    const auto& s = segments.segments[k];
    const Descriptors& e = all[k];
    EXPECT_EQ(e.status, Status::kOk);
    EXPECT_EQ(e.points_used, s.count);
    EXPECT_EQ(e.points_invalid + e.points_over_capacity, 0u);
    for (const float v : e.values) ASSERT_TRUE(std::isfinite(v));
    // The segmenter's box uses the same principal axis but sorts length >= width; the extent
    // along the major axis may be the shorter one (an L-shaped car).
    EXPECT_NEAR(std::max(e.values[0], e.values[1]), s.box.length, 0.05 + 0.02 * s.box.length);
    EXPECT_NEAR(std::min(e.values[0], e.values[1]), s.box.width, 0.05 + 0.02 * s.box.length);
    EXPECT_NEAR(e.values[2], s.z_max - s.z_min, 1e-3);
    ++checked;
  }
  EXPECT_EQ(checked, segments.segments.size());
}

TEST(DescriptorsKitti, EverySegmentOfObjectFrame000001HasFiniteDescriptorsWithoutAllocation) {
  STAC_REQUIRE_SHARED_DATA("kitti-object/velodyne/000001.bin");
  check_scan("kitti-object/velodyne/000001.bin");
}

TEST(DescriptorsKitti, EverySegmentOfOdometryScan000000HasFiniteDescriptorsWithoutAllocation) {
  STAC_REQUIRE_SHARED_DATA("kitti/000000.bin");
  check_scan("kitti/000000.bin");
}

}  // namespace
}  // namespace stac::descriptors
