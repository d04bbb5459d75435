#include "ego/ego_estimator.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "drivers/applanix/groups.hpp"

namespace stac::ego {
namespace {

constexpr double kOffset = 18.0;  // GPS - UTC, s
constexpr std::uint32_t kWeek = 2394;
constexpr Geodetic kOrigin{44.2449408681, -76.5096210157, 80.0};

// A POS LV stream: Group 3 (week, offset) then Group 1 at 200 Hz driving east at 10 m/s.
struct InsStream {
  applanix::StreamParser parser;
  std::vector<std::uint8_t> bytes = std::vector<std::uint8_t>(4096);

  // Parses the first n bytes of `bytes` into the estimator.
  void feed(std::size_t n, EgoEstimator& ego) {
    applanix::Parsed m;
    parser.feed(std::span<const std::uint8_t>(bytes.data(), n));
    while (parser.next(m)) ego.add_ins(m, parser);
  }
  std::size_t group3() {
    applanix::Group3 g;
    g.gps_week = kWeek;
    g.gps_utc_offset_s = kOffset;
    applanix::TimeDistance t;
    t.time1_s = 100.0;
    t.time_types = 0x01;
    return applanix::encode_group3(g, t, bytes);
  }
  std::size_t group1(double sow, double east_m, std::uint8_t alignment = 0) {
    applanix::Group1 g;
    // 1 deg of longitude at this latitude is about 79.8 km: a local east step.
    g.latitude_deg = kOrigin.lat_deg;
    g.longitude_deg = kOrigin.lon_deg + east_m / 79'800.0;
    g.altitude_m = kOrigin.alt_m;
    g.heading_deg = 90.0;
    g.east_velocity_mps = 10.0f;
    g.alignment_status = alignment;
    applanix::TimeDistance t;
    t.time1_s = sow;
    t.time_types = 0x01;  // time1 GPS
    return applanix::encode_group1(g, t, bytes);
  }
};

TEST(EgoEstimator, InsFixesBecomeUtcPosesInTheLocalFrame) {
  LocalFrame frame(kOrigin);
  PoseHistory history(PoseHistoryConfig{.capacity = 100});
  EgoEstimator ego(EgoEstimatorConfig{}, frame, history);
  InsStream s;
  auto push = [&](std::size_t n) { s.feed(n, ego); };
  push(s.group1(100.0, 0.0));  // before any Group 3: no absolute time yet
  EXPECT_EQ(ego.counters().no_absolute_time, 1u);
  push(s.group3());
  push(s.group1(100.005, 0.05));
  push(s.group1(100.010, 0.10, 7));  // not aligned: skipped
  EXPECT_EQ(ego.counters().ins_fixes, 1u);
  EXPECT_EQ(ego.counters().not_aligned, 1u);
  const std::int64_t utc = gps_to_utc_ns(
      static_cast<std::int64_t>(kWeek) * 604800 * 1'000'000'000 + 100'005'000'000, kOffset);
  EXPECT_EQ(utc, 315'964'800'000'000'000 +
                     static_cast<std::int64_t>(kWeek) * 604800 * 1'000'000'000 + 100'005'000'000 -
                     18'000'000'000);
  const PoseLookup l = history.at(utc);
  ASSERT_EQ(l.status, PoseStatus::kInterpolated);
  EXPECT_NEAR(l.pose.position_m.x(), 0.05, 0.01);
  EXPECT_NEAR(l.pose.velocity_mps.x(), 10.0, 1e-6);
  EXPECT_EQ(ego.source(utc), EgoSource::kIns);
}

// A Group 1 with a valid checksum and impossible values (NaN, off the Earth) is skipped and
// counted; with the origin taken from the first fix, it does not become the origin, and the
// fixes after it are poses.
TEST(EgoEstimator, AFixWithImpossibleValuesIsSkippedAndNeverTheOrigin) {
  LocalFrame frame;  // origin: the first fix
  PoseHistory history(PoseHistoryConfig{.capacity = 100});
  EgoEstimator ego(EgoEstimatorConfig{}, frame, history);
  InsStream s;
  s.feed(s.group3(), ego);
  const auto bad = [&](double sow, auto&& spoil) {
    applanix::Group1 g;
    g.latitude_deg = kOrigin.lat_deg;
    g.longitude_deg = kOrigin.lon_deg;
    g.altitude_m = kOrigin.alt_m;
    spoil(g);
    applanix::TimeDistance t;
    t.time1_s = sow;
    t.time_types = 0x01;
    s.feed(applanix::encode_group1(g, t, s.bytes), ego);
  };
  bad(100.000,
      [](applanix::Group1& g) { g.latitude_deg = std::numeric_limits<double>::quiet_NaN(); });
  bad(100.001, [](applanix::Group1& g) { g.latitude_deg = 1e308; });
  bad(100.002, [](applanix::Group1& g) { g.altitude_m = std::numeric_limits<double>::infinity(); });
  bad(100.003, [](applanix::Group1& g) { g.north_velocity_mps = 1e6f; });
  EXPECT_EQ(ego.counters().impossible, 4u);
  EXPECT_EQ(ego.counters().ins_fixes, 0u);
  for (int i = 1; i <= 3; ++i) s.feed(s.group1(100.0 + 0.005 * i, 0.05 * i), ego);
  EXPECT_EQ(ego.counters().ins_fixes, 3u);
  EXPECT_EQ(ego.counters().rejected, 0u);
  EXPECT_NEAR(frame.origin().lat_deg, kOrigin.lat_deg, 1e-9);
  EXPECT_NEAR(frame.origin().lon_deg, kOrigin.lon_deg + 0.05 / 79'800.0, 1e-9);
}

// One fix whose time jumped an hour ahead (a corrupted message with a valid checksum) is dropped
// once the next fix shows the time going on from before it; the INS back after a 5 s outage is
// taken at its second fix, with the first.
TEST(EgoEstimator, AFixThatJumpsAheadAloneIsDroppedAndTheInsBackAfterAnOutageIsTaken) {
  LocalFrame frame(kOrigin);
  PoseHistory history(PoseHistoryConfig{.capacity = 4096});
  EgoEstimator ego(EgoEstimatorConfig{}, frame, history);
  InsStream s;
  s.feed(s.group3(), ego);
  for (int i = 0; i < 100; ++i) {
    const double sow = 100.0 + 0.005 * i;
    s.feed(s.group1(i == 50 ? sow + 3600.0 : sow, 0.05 * i), ego);
  }
  EXPECT_EQ(ego.counters().time_jumps, 1u);
  EXPECT_EQ(ego.counters().rejected, 0u);
  EXPECT_EQ(ego.counters().ins_fixes, 99u);
  s.feed(s.group1(105.5, 55.0), ego);        // 5 s of silence, then fixes again
  EXPECT_EQ(ego.counters().ins_fixes, 99u);  // held until the next one
  s.feed(s.group1(105.505, 55.05), ego);
  EXPECT_EQ(ego.counters().ins_fixes, 101u);
  EXPECT_EQ(ego.counters().time_jumps, 1u);
  EXPECT_EQ(ego.counters().rejected, 0u);
}

// Issue 31: a looping replay (time back by the capture's length) and two fixes dated an hour
// ahead both used to lose the pose for the rest of the run.
TEST(EgoEstimator, TheTimeGoingBackStartsANewTimelineOnceTheNextFixConfirmsIt) {
  LocalFrame frame(kOrigin);
  PoseHistory history(PoseHistoryConfig{.capacity = 4096});
  EgoEstimator ego(EgoEstimatorConfig{}, frame, history);
  InsStream s;
  s.feed(s.group3(), ego);
  for (int pass = 0; pass < 3; ++pass)
    for (int i = 0; i < 400; ++i) s.feed(s.group1(100.0 + 0.005 * i, 0.05 * i), ego);  // 2 s
  // Each pass after the first: one fix held, then the new timeline.
  EXPECT_EQ(ego.counters().backward_jumps, 2u);
  EXPECT_EQ(ego.counters().ins_fixes, 1200u);
  EXPECT_EQ(ego.counters().rejected, 0u);
  // The history answers for the third pass's times (UTC = GPS week + sow - offset).
  const std::int64_t utc = ego::gps_to_utc_ns(
      static_cast<std::int64_t>(kWeek) * 604'800'000'000'000LL + 101'000'000'000LL, kOffset);
  const PoseLookup at = history.at(utc);
  ASSERT_TRUE(at.ok()) << to_string(at.status);
  EXPECT_NEAR(at.pose.position_m.x(), 10.0, 0.1);  // 1 s in at 10 m/s east

  // Two fixes an hour ahead (confirming each other), then the true time again.
  for (int i = 0; i < 2; ++i) s.feed(s.group1(3700.0 + 0.005 * i, 20.0), ego);
  const std::uint64_t before = ego.counters().ins_fixes;
  for (int i = 400; i < 410; ++i) s.feed(s.group1(100.0 + 0.005 * i, 0.05 * i), ego);
  EXPECT_EQ(ego.counters().backward_jumps, 3u);
  EXPECT_EQ(ego.counters().ins_fixes, before + 10u);  // none lost but the one held, then taken
  const PoseLookup later = history.at(ego::gps_to_utc_ns(
      static_cast<std::int64_t>(kWeek) * 604'800'000'000'000LL + 102'020'000'000LL, kOffset));
  EXPECT_TRUE(later.ok()) << to_string(later.status);
}

TEST(EgoEstimator, CanOdometryCarriesThePoseWhenTheInsGoesSilent) {
  LocalFrame frame(kOrigin);
  PoseHistory history(PoseHistoryConfig{.capacity = 1000});
  EgoEstimator ego(EgoEstimatorConfig{}, frame, history);
  InsStream s;
  auto push = [&](std::size_t n) { s.feed(n, ego); };
  push(s.group3());
  const std::int64_t t0 = gps_to_utc_ns(
      static_cast<std::int64_t>(kWeek) * 604800 * 1'000'000'000 + 200'000'000'000, kOffset);
  for (int i = 0; i <= 20; ++i) push(s.group1(200.0 + 0.005 * i, 0.05 * i));  // 0.1 s of INS
  ASSERT_EQ(ego.counters().ins_fixes, 21u);
  const std::int64_t last_fix = t0 + 100'000'000;
  // Then only CAN: 10 m/s, turning left at 10 deg/s, for one second at 100 Hz.
  for (int i = 1; i <= 100; ++i) {
    can::OdometryUpdate u;
    u.stamp_ns = last_fix + i * 10'000'000;
    u.has_speed = u.has_yaw_rate = true;
    u.speed_mps = 10.0;
    u.yaw_rate_dps = 10.0;
    ego.add_odometry(u);
  }
  EXPECT_GT(ego.counters().dead_reckoned, 80u);  // 200 Hz at most, from 100 Hz frames
  const std::int64_t end = last_fix + 1'000'000'000;
  EXPECT_EQ(ego.source(end), EgoSource::kDeadReckoning);
  const PoseLookup l = history.at(end - 5'000'000);
  ASSERT_TRUE(l.ok()) << to_string(l.status);
  // An arc of radius 57.3 m from (1.0, 0) heading east, turning left (counter-clockwise).
  const double r = 10.0 / (10.0 * std::numbers::pi / 180.0);
  const double yaw = 0.995 * 10.0 * std::numbers::pi / 180.0;
  EXPECT_NEAR(l.pose.position_m.x(), 1.0 + r * std::sin(yaw), 0.15);
  EXPECT_NEAR(l.pose.position_m.y(), r * (1.0 - std::cos(yaw)), 0.15);
  EXPECT_EQ(ego.source(end + 1'000'000'000), EgoSource::kLost);  // and then odometry stops too
}

}  // namespace
}  // namespace stac::ego
