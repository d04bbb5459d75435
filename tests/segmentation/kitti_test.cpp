// The segmenter on real HDL-64E scans (KITTI): plausible segment counts, no overflow, no
// allocation, and the labeled objects of KITTI object frame 000001 found as segments.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "perception/segmentation/segmenter.hpp"
#include "rt/testing/alloc_counter.hpp"
#include "shared_data.hpp"

namespace stac::segmentation {
namespace {

PointView view(const std::vector<float>& xyzi) {
  return {xyzi.data(), xyzi.size() / 4, 16};
}

TEST(SegmenterKitti, OdometryScansSegmentPlausiblyWithoutOverflowOrAllocation) {
  STAC_REQUIRE_SHARED_DATA("kitti/000005.bin");
  std::vector<std::vector<float>> scans;
  for (int i = 0; i < 6; ++i) {
    scans.push_back(testing::read_kitti_bin("kitti/00000" + std::to_string(i) + ".bin"));
  }
  Segmenter segmenter(SegmenterConfig{});
  Segments out = segmenter.make_segments();
  segmenter.segment(view(scans[0]), out);  // warm-up (first touch of the grids)
  std::vector<std::size_t> counts;
  counts.reserve(scans.size());
  rt::testing::AllocationCounter counter;
  for (const auto& scan : scans) {
    segmenter.segment(view(scan), out);
    const SegmentCounters& k = out.counters;
    counts.push_back(out.segments.size());
    EXPECT_EQ(k.ignored_over_capacity + k.dropped_cell_overflow + k.dropped_segment_overflow, 0u);
    EXPECT_GT(k.points_in, 110000u);
    EXPECT_GT(k.ground_points, k.points_in / 3);  // an urban street: much of the scan is road
    EXPECT_GT(k.obstacle_points, k.points_in / 10);
    EXPECT_EQ(k.ignored_invalid + k.ignored_out_of_range + k.ignored_below + k.ground_points +
                  k.ignored_above + k.obstacle_points,
              k.points_in);
    std::uint64_t in_segments = 0;
    for (const Segment& s : out.segments) {
      in_segments += s.count;
      EXPECT_GE(s.box.length, s.box.width);
      EXPECT_LE(s.z_min, s.z_max);
    }
    EXPECT_EQ(in_segments, out.point_indices.size());
  }
  counter.stop();
  EXPECT_EQ(counter.allocations(), 0u);
  for (const std::size_t n : counts) {
    EXPECT_GE(n, 30u);
    EXPECT_LE(n, 600u);
  }
}

// KITTI object labels: camera-rectified boxes mapped into the Velodyne frame.
struct LabelBox {
  std::string type;
  Eigen::Vector3d centre;  // sensor frame (m)
  double length, width, height, yaw;
};

Eigen::Matrix<double, 3, 4> read_matrix(const std::string& calib, const std::string& key,
                                        int cols) {
  std::ifstream f(testing::shared_data(calib));
  std::string line;
  Eigen::Matrix<double, 3, 4> m = Eigen::Matrix<double, 3, 4>::Zero();
  while (std::getline(f, line)) {
    if (line.rfind(key + ":", 0) != 0) continue;
    std::istringstream in(line.substr(key.size() + 1));
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < cols; ++c) in >> m(r, c);
    }
  }
  return m;
}

std::vector<LabelBox> read_labels(const std::string& frame) {
  const std::string calib = "kitti-object/calib/" + frame + ".txt";
  const Eigen::Matrix3d r0 = read_matrix(calib, "R0_rect", 3).leftCols<3>();
  const Eigen::Matrix<double, 3, 4> tr = read_matrix(calib, "Tr_velo_to_cam", 4);
  const Eigen::Matrix3d rot = tr.leftCols<3>();
  const Eigen::Vector3d t = tr.col(3);
  std::ifstream f(testing::shared_data("kitti-object/label_2/" + frame + ".txt"));
  std::vector<LabelBox> boxes;
  std::string type;
  double trunc, alpha, l2, t2, r2, b2, h, w, l, x, y, z, ry;
  int occluded;
  while (f >> type >> trunc >> occluded >> alpha >> l2 >> t2 >> r2 >> b2 >> h >> w >> l >> x >> y >>
         z >> ry) {
    if (type == "DontCare") continue;
    const Eigen::Vector3d rect(x, y - h / 2, z);  // label: bottom centre, camera y down
    const Eigen::Vector3d cam = r0.inverse() * rect;
    boxes.push_back({type, rot.transpose() * (cam - t), l, w, h, -ry - M_PI / 2});
  }
  return boxes;
}

bool in_box(const LabelBox& b, float x, float y, float z, double margin_m = 0.0) {
  const double c = std::cos(b.yaw), s = std::sin(b.yaw);
  const double dx = x - b.centre.x(), dy = y - b.centre.y();
  const double u = c * dx + s * dy, v = -s * dx + c * dy;
  return std::fabs(u) <= b.length / 2 + margin_m && std::fabs(v) <= b.width / 2 + margin_m &&
         std::fabs(z - b.centre.z()) <= b.height / 2 + margin_m;
}

// Each labeled object with at least min_segment_points returns in its box is one segment: the
// segment holding most of its points has its centroid within 1 m of the label box (the centroid
// of the visible side: the 12 m truck shows only its rear at 70 m) and most of its points inside.
TEST(SegmenterKitti, LabeledTruckCarAndCyclistOfObjectFrame000001AreSegments) {
  STAC_REQUIRE_SHARED_DATA("kitti-object/velodyne/000001.bin");
  const auto cloud = testing::read_kitti_bin("kitti-object/velodyne/000001.bin");
  const auto labels = read_labels("000001");
  ASSERT_EQ(labels.size(), 3u);  // Truck, Car, Cyclist
  const SegmenterConfig config;
  Segmenter segmenter(config);
  Segments out = segmenter.make_segments();
  segmenter.segment(view(cloud), out);
  std::vector<int> owner(cloud.size() / 4, -1);
  for (std::size_t k = 0; k < out.segments.size(); ++k) {
    for (const std::uint32_t i : out.indices(out.segments[k])) owner[i] = static_cast<int>(k);
  }
  int checked = 0;
  for (const LabelBox& label : labels) {
    std::vector<int> votes(out.segments.size(), 0);
    std::uint32_t inside = 0;
    for (std::size_t i = 0; i < owner.size(); ++i) {
      if (!in_box(label, cloud[4 * i], cloud[4 * i + 1], cloud[4 * i + 2])) continue;
      ++inside;
      if (owner[i] >= 0) ++votes[static_cast<std::size_t>(owner[i])];
    }
    if (inside < config.min_segment_points) continue;  // too few returns to be a segment
    ++checked;
    SCOPED_TRACE(label.type + " with " + std::to_string(inside) + " returns in its box");
    ASSERT_FALSE(votes.empty());
    const auto best =
        static_cast<std::size_t>(std::max_element(votes.begin(), votes.end()) - votes.begin());
    const Segment& s = out.segments[best];
    EXPECT_GE(votes[best] * 2, static_cast<int>(inside));  // the segment holds most of the object
    EXPECT_TRUE(in_box(label, s.centroid[0], s.centroid[1], s.centroid[2], 1.0))
        << "centroid (" << s.centroid[0] << ", " << s.centroid[1] << ", " << s.centroid[2] << ")";
    int in_label = 0;
    for (const std::uint32_t i : out.indices(s))
      in_label += in_box(label, cloud[4 * i], cloud[4 * i + 1], cloud[4 * i + 2], 0.5) ? 1 : 0;
    EXPECT_GE(in_label * 10, static_cast<int>(s.count) * 8)
        << "segment of " << s.count << " points";  // not merged
  }
  EXPECT_EQ(checked, 3);
}

}  // namespace
}  // namespace stac::segmentation
