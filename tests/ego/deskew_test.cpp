#include "ego/deskew.hpp"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <numbers>
#include <optional>

#include "drivers/velodyne/scan_assembler.hpp"
#include "rt/testing/alloc_counter.hpp"
#include "shared_data.hpp"
#include "sim/lidar.hpp"
#include "sim/world.hpp"

namespace stac::ego {
namespace {

constexpr const char* kYaml = "velodyne/calib/rosdrivers_64e_s2.1-sztaki.yaml";
constexpr double kYawRate = 30.0 * std::numbers::pi / 180.0;  // rad/s, turning left
constexpr double kSpeed = 5.0;                                // m/s
constexpr double kMount = 1.73;                               // sensor above the ego origin
constexpr std::int64_t kStart = 1'767'268'800'000'000'000;    // pose clock = scan clock here

// The ego drives an exact arc: every pose is known in closed form.
sim::EgoState ego_at(double t) {
  sim::EgoState e;
  e.yaw = kYawRate * t;
  e.x = kSpeed / kYawRate * std::sin(e.yaw);
  e.y = kSpeed / kYawRate * (1.0 - std::cos(e.yaw));
  e.speed = kSpeed;
  e.yaw_rate = kYawRate;
  return e;
}

PoseSample pose_at(double t) {
  const sim::EgoState e = ego_at(t);
  PoseSample p;
  p.stamp_ns = kStart + std::llround(t * 1e9);
  p.position_m = {e.x, e.y, e.z};
  p.attitude = from_roll_pitch_yaw(e.roll, e.pitch, e.yaw);
  p.velocity_mps = {kSpeed * std::cos(e.yaw), kSpeed * std::sin(e.yaw), 0.0};
  p.angular_rate_rps = {0.0, 0.0, kYawRate};
  return p;
}

// Largest distance of the wall points (above the ground) from their best-fit line in XY.
double wall_bend_m(const velodyne::Scan& scan) {
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  int n = 0;
  for (const auto& p : scan.points) {
    if (p.z > -1.3f) mean += Eigen::Vector2d(p.x, p.y), ++n;
  }
  EXPECT_GT(n, 2000);
  mean /= n;
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  for (const auto& p : scan.points) {
    if (p.z > -1.3f) {
      const Eigen::Vector2d d = Eigen::Vector2d(p.x, p.y) - mean;
      cov += d * d.transpose();
    }
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(cov);
  const Eigen::Vector2d normal = eig.eigenvectors().col(0);  // smallest eigenvalue
  double worst = 0;
  for (const auto& p : scan.points) {
    if (p.z > -1.3f)
      worst = std::max(worst, std::abs((Eigen::Vector2d(p.x, p.y) - mean).dot(normal)));
  }
  return worst;
}

class TurningPastAWall : public ::testing::Test {
 protected:
  void SetUp() override {
    STAC_REQUIRE_SHARED_DATA(kYaml);
    auto c = velodyne::load_calibration(stac::testing::shared_data(kYaml));
    ASSERT_TRUE(c) << c.error().message;
    calibration = *c;
    sim::GroundConfig ground;
    ground.slope_x = ground.slope_y = ground.wave_amplitude = 0.0;
    ground.has_road = false;
    sim::Actor wall;
    wall.id = 1;
    wall.cls = sim::ObjectClass::kWall;
    wall.shape = sim::Shape::kBox;
    wall.size = {0.3, 40.0, 4.0};  // 40 m long across the sensor's forward direction
    wall.reflectivity = 0.5;
    wall.path.points = {{15.0, 0.0, 0.0}};
    world.emplace(ground, std::vector<sim::Actor>{wall});
    sim::LidarConfig lc;
    lc.range_noise_m = 0.0;  // the bend, not the noise, is measured
    lc.dropout = 0.0;
    sim::LidarSim lidar(calibration, lc, *world, ego_at);

    velodyne::ScanAssemblerConfig ac;
    ac.decoder.model = velodyne::Model::kS2_1;
    velodyne::ScanAssembler assembler(calibration, ac);
    scan.emplace(velodyne::scan_capacity(ac));
    assembler.begin(*scan);
    std::array<std::uint8_t, velodyne::kPacketSize> bytes{};
    for (std::uint32_t k = 0; k < 1200; ++k) {  // 0.35 s: one complete scan after the first cut
      double first_s = 0;
      lidar.make_packet(k, bytes, first_s, {});
      if (assembler.add_packet(bytes, kStart + std::llround(first_s * 1e9))) {
        if (scan->header.complete()) break;
        assembler.begin(*scan);
      }
    }
    ASSERT_TRUE(scan->header.complete());
    for (double t = -0.1; t < 0.5; t += 0.005) ASSERT_TRUE(history.push(pose_at(t)));
    config.vehicle_T_sensor.translation() = Eigen::Vector3d(0, 0, kMount);
  }

  velodyne::Calibration calibration;
  std::optional<sim::World> world;
  std::optional<velodyne::Scan> scan;
  PoseHistory history{PoseHistoryConfig{.capacity = 400}};
  DeskewConfig config;
};

TEST_F(TurningPastAWall, IsBentBeforeDeskewAndStraightWithin5cmAfter) {
  const double before = wall_bend_m(*scan);
  Deskewer deskew(config);
  const DeskewResult r = deskew.apply(*scan, history, 0);
  ASSERT_TRUE(r.ok()) << to_string(r.status);
  EXPECT_EQ(r.points_without_pose, 0u);
  const double after = wall_bend_m(*scan);
  RecordProperty("bend_before_mm", static_cast<int>(before * 1000));
  RecordProperty("bend_after_mm", static_cast<int>(after * 1000));
  EXPECT_GT(before, 0.30) << "the sweep should visibly bend the wall";
  EXPECT_LT(after, 0.05) << "before " << before;
  // The wall is where the world says, seen from the sensor at the scan's last firing.
  const Eigen::Isometry3d expected =
      to_isometry(pose_at(static_cast<double>(scan->header.end_stamp_ns - kStart) * 1e-9)) *
      config.vehicle_T_sensor;
  EXPECT_NEAR((r.world_T_sensor.translation() - expected.translation()).norm(), 0.0, 1e-6);
  int wall_points = 0;
  for (const auto& p : scan->points) {
    if (p.z <= -1.3f) continue;
    const Eigen::Vector3d w = r.world_T_sensor * Eigen::Vector3d(p.x, p.y, p.z);
    EXPECT_NEAR(w.x(), 15.0 - 0.15, 0.05);  // the wall's near face
    ++wall_points;
  }
  EXPECT_GT(wall_points, 2000);
}

TEST_F(TurningPastAWall, WithoutPosesTheScanIsLeftAloneAndSaysWhy) {
  PoseHistory empty(PoseHistoryConfig{});
  const float x0 = scan->points[0].x;
  Deskewer deskew(config);
  const DeskewResult r = deskew.apply(*scan, empty, 0);
  EXPECT_EQ(r.status, PoseStatus::kEmpty);
  EXPECT_EQ(scan->points[0].x, x0);
  // Poses that stop in the middle of the scan: the later points are counted, not guessed.
  PoseHistory half(PoseHistoryConfig{.capacity = 400, .max_extrapolation_ns = 0});
  const double mid = static_cast<double>(scan->header.stamp_ns - kStart) * 1e-9 + 0.05;
  for (double t = -0.1; t < mid; t += 0.005) ASSERT_TRUE(half.push(pose_at(t)));
  EXPECT_EQ(deskew.apply(*scan, half, 0).status, PoseStatus::kTooNew);
}

TEST_F(TurningPastAWall, DeskewAllocatesNothing) {
  Deskewer deskew(config);
  rt::testing::AllocationCounter counter;
  const DeskewResult r = deskew.apply(*scan, history, 0);
  counter.stop();
  EXPECT_TRUE(r.ok());
  EXPECT_EQ(counter.allocations(), 0u);
}

}  // namespace
}  // namespace stac::ego
