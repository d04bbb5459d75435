#include "ego/local_frame.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace stac::ego {
namespace {

// The origin of the real Applanix capture in ../shared/data/applanix (Kingston, Ontario).
constexpr Geodetic kOrigin{44.2449408681, -76.5096210157, 80.0};

Eigen::Vector3d forward(const Eigen::Quaterniond& q) {
  return q * Eigen::Vector3d::UnitX();
}
Eigen::Vector3d left(const Eigen::Quaterniond& q) {
  return q * Eigen::Vector3d::UnitY();
}

TEST(LocalFrame, IsEastNorthUpAroundTheOrigin) {
  LocalFrame f(kOrigin);
  EXPECT_NEAR(f.to_local(kOrigin).norm(), 0.0, 1e-9);
  const Eigen::Vector3d north =
      f.to_local({kOrigin.lat_deg + 0.001, kOrigin.lon_deg, kOrigin.alt_m});
  EXPECT_NEAR(north.y(), 111.1, 0.2);  // 0.001 deg of latitude
  EXPECT_NEAR(north.x(), 0.0, 1e-3);
  const Eigen::Vector3d east =
      f.to_local({kOrigin.lat_deg, kOrigin.lon_deg + 0.001, kOrigin.alt_m});
  EXPECT_NEAR(east.x(), 111.3 * std::cos(kOrigin.lat_deg * std::numbers::pi / 180.0), 0.2);
  const Eigen::Vector3d up = f.to_local({kOrigin.lat_deg, kOrigin.lon_deg, kOrigin.alt_m + 5.0});
  EXPECT_NEAR(up.z(), 5.0, 1e-6);
}

TEST(LocalFrame, AnchorsAtTheFirstFixWithoutAConfiguredOrigin) {
  LocalFrame f;
  EXPECT_FALSE(f.anchored());
  InsFix fix;
  fix.position = kOrigin;
  const PoseSample p = f.pose(fix);
  EXPECT_TRUE(f.anchored());
  EXPECT_NEAR(p.position_m.norm(), 0.0, 1e-9);
  EXPECT_NEAR(f.origin().lat_deg, kOrigin.lat_deg, 1e-12);
}

TEST(LocalFrame, HeadingPitchAndRollFollowTheApplanixConventions) {
  // Heading 0 = north, 90 = east (clockwise from north): ENU yaw = 90 deg - heading.
  EXPECT_NEAR((forward(LocalFrame::attitude_enu(0, 0, 0)) - Eigen::Vector3d::UnitY()).norm(), 0,
              1e-12);
  EXPECT_NEAR((forward(LocalFrame::attitude_enu(0, 0, 90)) - Eigen::Vector3d::UnitX()).norm(), 0,
              1e-12);
  EXPECT_NEAR((left(LocalFrame::attitude_enu(0, 0, 90)) - Eigen::Vector3d::UnitY()).norm(), 0,
              1e-12);
  // Positive pitch = nose up; positive roll = right side down, so the left side goes up.
  EXPECT_NEAR(forward(LocalFrame::attitude_enu(0, 10, 0)).z(),
              std::sin(10 * std::numbers::pi / 180), 1e-12);
  EXPECT_NEAR(left(LocalFrame::attitude_enu(10, 0, 0)).z(), std::sin(10 * std::numbers::pi / 180),
              1e-12);
}

TEST(LocalFrame, VelocityAndRatesAreRotatedIntoTheVehicleAndWorldFrames) {
  LocalFrame f(kOrigin);
  InsFix fix;
  fix.position = kOrigin;
  fix.heading_deg = 90;
  fix.velocity_ned_mps = {1.0, 2.0, -0.5};      // north, east, down
  fix.angular_rate_frd_dps = {0.0, 0.0, 30.0};  // turning right (clockwise seen from above)
  const PoseSample p = f.pose(fix);
  EXPECT_NEAR((p.velocity_mps - Eigen::Vector3d(2.0, 1.0, 0.5)).norm(), 0, 1e-12);
  EXPECT_NEAR(p.angular_rate_rps.z(), -30.0 * std::numbers::pi / 180, 1e-12);  // z up: negative
}

TEST(LocalFrame, NorthAtAFarFixIsTheLocalNorthSeenFromTheOrigin) {
  // 20 km east the meridians converge: north there is not +y of the origin's frame.
  LocalFrame f(kOrigin);
  const Geodetic far{kOrigin.lat_deg, kOrigin.lon_deg + 0.25, kOrigin.alt_m};
  InsFix fix;
  fix.position = far;
  const PoseSample p = f.pose(fix);
  const Eigen::Vector3d step =
      f.to_local({far.lat_deg + 1e-5, far.lon_deg, far.alt_m}) - p.position_m;
  const Eigen::Vector3d x = forward(p.attitude);
  EXPECT_NEAR(x.dot(step.normalized()), 1.0, 1e-9);
  EXPECT_GT(std::abs(x.x()), 1e-3);  // and the convergence is really there
}

}  // namespace
}  // namespace stac::ego
