// The virtual POS LV and vehicle CAN bus, decoded back with the project's own readers.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>
#include <vector>

#include "drivers/applanix/stream_parser.hpp"
#include "drivers/can/dbc.hpp"
#include "drivers/can/odometry.hpp"
#include "ego/local_frame.hpp"
#include "ego/pose.hpp"
#include "sim/ins.hpp"
#include "sim/vehicle_can.hpp"
#include "test_paths.hpp"

namespace stac::sim {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;
constexpr std::int64_t kStartNs = 1'767'268'800'000'000'000;  // 2026-01-01 12:00:00 UTC

// A left-turning circle (radius 40 m, 8 m/s) 5 km from the origin on a sloped, tilted road, so
// that heading, pitch, roll, climb and meridian convergence are all exercised.
EgoState circle(double t) {
  const double radius = 40.0, speed = 8.0, w = speed / radius;
  const double a = w * t;
  EgoState e;
  e.x = 5000.0 + radius * std::sin(a);
  e.y = -3000.0 + radius * (1.0 - std::cos(a));
  e.z = 12.0 + 0.03 * e.x * 0.001 + 0.5 * std::sin(0.2 * t);
  e.yaw = std::remainder(a, 2 * kPi);
  e.pitch = -0.04 * std::cos(0.3 * t);  // nose up is negative in the sim
  e.roll = 0.03 * std::sin(0.25 * t);
  e.speed = speed;
  e.yaw_rate = w;
  return e;
}

struct DecodedGroup1 {
  applanix::Group1 g;
  applanix::TimeDistance time;
  std::optional<std::int64_t> gps_ns;
};

struct Decoded {
  std::vector<DecodedGroup1> group1;
  std::vector<std::pair<std::int64_t, std::uint16_t>> others;  // GPS ns (of time1), group id
  std::vector<applanix::Group3> group3;
  std::vector<std::int64_t> stamps;  // InsMessage stamps, all
};

Decoded run_ins(const InsConfig& config, InsSim::EgoFn ego, double seconds) {
  InsSim ins(config, std::move(ego));
  applanix::StreamParser parser;
  Decoded d;
  const std::int64_t end = config.start_ns + std::llround(seconds * 1e9);
  while (ins.next_stamp_ns() <= end) {
    const InsMessage m = ins.next();
    d.stamps.push_back(m.stamp_ns);
    parser.feed(m.bytes);
    applanix::Parsed p;
    int n = 0;
    while (parser.next(p)) {
      ++n;
      if (const auto* g1 = std::get_if<applanix::Group1>(&p.content)) {
        EXPECT_EQ(m.group, 1);
        d.group1.push_back({*g1, p.time, p.time1_gps_ns});
      } else {
        d.others.emplace_back(p.time1_gps_ns.value_or(-1), m.group);
        if (const auto* g3 = std::get_if<applanix::Group3>(&p.content)) d.group3.push_back(*g3);
      }
    }
    EXPECT_EQ(n, 1) << "each message is one whole group";
  }
  EXPECT_EQ(parser.counters().garbage_bytes, 0u);
  EXPECT_EQ(parser.counters().bad_checksum, 0u);
  EXPECT_EQ(parser.counters().malformed, 0u);
  return d;
}

double angle_between_deg(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  return Eigen::AngleAxisd(a.inverse() * b).angle() / kDeg;
}

TEST(SimIns, GpsTimeOfUtcCountsLeapSecondsAndWeeks) {
  // 2026-01-01 is 16797 days after 1980-01-06: week 2399 (16793 days) + 4 days; 12:00:00 UTC is
  // 12:00:18 GPS.
  const std::int64_t gps_ns = gps_ns_of_utc(kStartNs);
  const GpsTime t = gps_time_of_gps_ns(gps_ns);
  EXPECT_EQ(t.week, 2399u);
  EXPECT_DOUBLE_EQ(t.seconds_of_week, 4 * 86400.0 + 12 * 3600.0 + 18.0);
  EXPECT_EQ(gps_ns_of_utc(kGpsEpochUnixS * 1'000'000'000LL, 0), 0);
}

// Every Group 1 decoded by the project's parser and turned into a pose by ego::LocalFrame gives
// the sim's ego state back: position within 1 cm, attitude within 0.01 deg.
TEST(SimIns, Group1ThroughLocalFrameGivesTheEgoBack) {
  InsConfig config;
  config.start_ns = kStartNs;
  const Decoded d = run_ins(config, circle, 3.0);
  ASSERT_EQ(d.group1.size(), 601u);
  ego::LocalFrame frame(config.origin);
  const std::int64_t start_gps = gps_ns_of_utc(kStartNs);
  for (std::size_t i = 0; i < d.group1.size(); ++i) {
    const DecodedGroup1& r = d.group1[i];
    ASSERT_TRUE(r.gps_ns.has_value() || i < 1) << "absolute time once a Group 3 gave the week";
    EXPECT_EQ(r.time.time_types, 0x01);
    const double t = static_cast<double>(i) * 0.005;
    EXPECT_NEAR(r.time.time1_s, gps_time_of_gps_ns(start_gps).seconds_of_week + t, 1e-9);
    EXPECT_NEAR(r.time.time2_s, config.pos_time_at_start_s + t, 1e-9);
    const EgoState e = circle(t);
    ego::InsFix fix;
    fix.position = {r.g.latitude_deg, r.g.longitude_deg, r.g.altitude_m};
    fix.roll_deg = r.g.roll_deg;
    fix.pitch_deg = r.g.pitch_deg;
    fix.heading_deg = r.g.heading_deg;
    fix.velocity_ned_mps = {r.g.north_velocity_mps, r.g.east_velocity_mps, r.g.down_velocity_mps};
    fix.angular_rate_frd_dps = {r.g.rate_longitudinal_dps, r.g.rate_transverse_dps,
                                r.g.rate_down_dps};
    const ego::PoseSample p = frame.pose(fix);
    EXPECT_NEAR((p.position_m - Eigen::Vector3d(e.x, e.y, e.z)).norm(), 0.0, 0.01) << "t " << t;
    EXPECT_LT(angle_between_deg(p.attitude, ego::from_roll_pitch_yaw(e.roll, e.pitch, e.yaw)), 0.01)
        << "t " << t;
    // Velocity: the speed along the yaw (no side slip) plus the climb.
    const double climb = (circle(t + 0.005).z - circle(t - 0.005).z) / 0.01;
    const Eigen::Vector3d v(e.speed * std::cos(e.yaw), e.speed * std::sin(e.yaw), climb);
    EXPECT_LT((p.velocity_mps - v).norm(), 1e-3) << "t " << t;
    EXPECT_NEAR(r.g.speed_mps, e.speed, 2e-3);
    // Body rates: a left turn at 0.2 rad/s is a negative down rate, within the attitude wobble.
    EXPECT_NEAR(p.angular_rate_rps.z(), e.yaw_rate, 0.01) << "t " << t;
    EXPECT_EQ(r.g.alignment_status, 0);
    // Centripetal acceleration v^2/r = 1.6 m/s^2 to the left (negative transverse in FRD).
    EXPECT_NEAR(r.g.accel_transverse_mps2, -1.6, 0.05);
  }
}

// The Applanix conventions spelled out: the sim's nose-up pitch is negative, Applanix's positive;
// a left-side-up roll is a right-side-down roll; yaw 0 (east) is heading 90.
TEST(SimIns, AttitudeSignsFollowTheApplanixConvention) {
  InsConfig config;
  config.start_ns = kStartNs;
  auto at = [&](double roll, double pitch, double yaw) {
    InsSim ins(config, [=](double) {
      EgoState e;
      e.roll = roll;
      e.pitch = pitch;
      e.yaw = yaw;
      return e;
    });
    return ins.group1_at(0.0);
  };
  const applanix::Group1 nose_up = at(0, -5 * kDeg, 0);
  EXPECT_NEAR(nose_up.pitch_deg, 5.0, 1e-9);
  EXPECT_NEAR(nose_up.heading_deg, 90.0, 1e-9);
  EXPECT_NEAR(at(3 * kDeg, 0, 0).roll_deg, 3.0, 1e-9);
  EXPECT_NEAR(at(0, 0, kPi / 2).heading_deg, 0.0, 1e-9);     // north
  EXPECT_NEAR(at(0, 0, -kPi / 2).heading_deg, 180.0, 1e-9);  // south
  EXPECT_NEAR(at(0, 0, kPi).heading_deg, 270.0, 1e-9);       // west
  const applanix::Group1 origin = at(0, 0, 0);
  EXPECT_NEAR(origin.latitude_deg, config.origin.lat_deg, 1e-12);
  EXPECT_NEAR(origin.longitude_deg, config.origin.lon_deg, 1e-12);
  EXPECT_NEAR(origin.altitude_m, config.origin.alt_m, 1e-6);
}

// 200 Hz on multiples of 5 ms of GPS time; Groups 2 and 3 right after the Group 1 of each whole
// GPS second, with the week and the 18 s GPS-UTC offset; message stamps in time order.
TEST(SimIns, GroupsTwoAndThreeOncePerGpsSecondAfterItsGroup1) {
  InsConfig config;
  config.start_ns = kStartNs + 2'345'678;  // not on the 5 ms grid
  const Decoded d = run_ins(config, circle, 2.5);
  ASSERT_FALSE(d.group1.empty());
  const std::int64_t start_gps = gps_ns_of_utc(config.start_ns);
  const std::int64_t first = (start_gps / 5'000'000 + 1) * 5'000'000;
  EXPECT_NEAR(d.group1.front().time.time1_s, gps_time_of_gps_ns(first).seconds_of_week, 1e-9);
  for (std::size_t i = 1; i < d.group1.size(); ++i) {
    EXPECT_NEAR(d.group1[i].time.time1_s - d.group1[i - 1].time.time1_s, 0.005, 1e-9);
  }
  // Whole seconds inside [start + 2.35 ms, start + 2.5 s]: GPS s + 1, + 2.
  ASSERT_EQ(d.others.size(), 4u);
  const std::int64_t second0 = (start_gps / 1'000'000'000 + 1) * 1'000'000'000;
  for (std::size_t k = 0; k < 2; ++k) {
    EXPECT_EQ(d.others[2 * k].second, 2);
    EXPECT_EQ(d.others[2 * k + 1].second, 3);
    // The first Group 2 comes before any Group 3 gave the week.
    if (k > 0) {
      EXPECT_EQ(d.others[2 * k].first, second0 + static_cast<std::int64_t>(k) * 1'000'000'000);
    }
    EXPECT_EQ(d.others[2 * k + 1].first, second0 + static_cast<std::int64_t>(k) * 1'000'000'000);
  }
  ASSERT_EQ(d.group3.size(), 2u);
  EXPECT_EQ(d.group3[0].gps_week, 2399u);
  EXPECT_EQ(d.group3[0].gps_utc_offset_s, 18.0);
  EXPECT_EQ(d.group3[0].solution_status, 7);
  EXPECT_EQ(d.group3[0].channel_count, 12u);
  for (std::size_t i = 1; i < d.stamps.size(); ++i) EXPECT_GE(d.stamps[i], d.stamps[i - 1]);
  // Group 1 stamps are the UTC of their GPS time.
  EXPECT_EQ(d.stamps.front(), config.start_ns + (first - start_gps));
}

can::Database vehicle_dbc() {
  auto db = can::load_dbc(std::filesystem::path(::stac::testing::source_dir()) /
                          "config/can/vehicle.dbc");
  EXPECT_TRUE(db) << db.error().message;
  return *db;
}

can::OdometrySignalMap vehicle_map() {
  return {"WheelSpeeds", "VehicleSpeed", "YawRate", "YawRate", 1.0};
}

// The frames decode to the ego's speed and yaw rate within the DBC's quantisation (0.01 km/h,
// 0.01 deg/s), at 50 and 100 Hz, and dead reckoning on them follows the circle.
TEST(SimCan, TurningDriveDecodesAndDeadReckonsOnTheCircle) {
  const can::Database db = vehicle_dbc();
  VehicleCanConfig config;
  config.start_ns = kStartNs;
  auto bus = VehicleCanSim::create(db, vehicle_map(), config, circle);
  ASSERT_TRUE(bus) << bus.error().message;
  auto decoder = can::OdometryDecoder::create(db, vehicle_map());
  ASSERT_TRUE(decoder);
  can::DeadReckoning dr(can::DeadReckoningConfig{});
  std::map<std::uint32_t, std::vector<std::int64_t>> stamps;
  const double seconds = 5.0;
  std::int64_t last = 0;
  can::Frame f;
  while (bus->next_stamp_ns() <= kStartNs + static_cast<std::int64_t>(seconds * 1e9)) {
    ASSERT_TRUE(bus->next(f));
    EXPECT_GE(f.stamp_ns, last);
    last = f.stamp_ns;
    EXPECT_EQ(f.dlc, 8);
    stamps[f.id].push_back(f.stamp_ns);
    const can::OdometryUpdate u = decoder->decode(f);
    ASSERT_TRUE(u.has_speed || u.has_yaw_rate);
    const EgoState e = circle(static_cast<double>(f.stamp_ns - kStartNs) * 1e-9);
    if (u.has_speed) {
      EXPECT_NEAR(u.speed_mps, e.speed, 0.005 / 3.6 + 1e-9);
    }
    if (u.has_yaw_rate) {
      EXPECT_NEAR(u.yaw_rate_dps, e.yaw_rate / kDeg, 0.005 + 1e-9);
    }
    dr.update(u);
  }
  EXPECT_EQ(stamps[0x1A0].size(), 250u);
  EXPECT_EQ(stamps[0x1B0].size(), 500u);
  EXPECT_EQ(stamps[0x1A0][1] - stamps[0x1A0][0], 20'000'000);
  EXPECT_EQ(stamps[0x1B0][1] - stamps[0x1B0][0], 10'000'000);
  // Dead reckoning starts at the first frame with both inputs, at the ego pose of that time;
  // compare displacements in the start vehicle frame.
  const double t0 = 0.0013;  // the first speed frame (after the first yaw-rate frame)
  const double t1 = static_cast<double>(dr.pose().stamp_ns - kStartNs) * 1e-9;
  const EgoState a = circle(t0), b = circle(t1);
  const double dx = b.x - a.x, dy = b.y - a.y;
  const double fwd = std::cos(a.yaw) * dx + std::sin(a.yaw) * dy;
  const double left = -std::sin(a.yaw) * dx + std::cos(a.yaw) * dy;
  EXPECT_NEAR(dr.pose().x_m, fwd, 0.05);
  EXPECT_NEAR(dr.pose().y_m, left, 0.05);
  EXPECT_NEAR(dr.pose().yaw_rad, std::remainder(b.yaw - a.yaw, 2 * kPi), 0.002);
  EXPECT_EQ(bus->counters().unencodable, 0u);
}

// A value outside its signal's range is not sent and is counted (the 16-bit yaw rate holds
// +-327.67 deg/s); a signal map naming a missing message is refused.
TEST(SimCan, OutOfRangeValuesAreCountedAndBadMapsRefused) {
  const can::Database db = vehicle_dbc();
  VehicleCanConfig config;
  config.start_ns = kStartNs;
  auto bus = VehicleCanSim::create(db, vehicle_map(), config, [](double) {
    EgoState e;
    e.speed = 5.0;
    e.yaw_rate = 7.0;  // 401 deg/s
    return e;
  });
  ASSERT_TRUE(bus);
  can::Frame f;
  int sent = 0;
  for (int i = 0; i < 30; ++i) sent += bus->next(f) ? 1 : 0;
  EXPECT_EQ(sent, 10);  // the speed frames of 0..0.2 s
  EXPECT_EQ(bus->counters().unencodable, 20u);
  can::OdometrySignalMap bad = vehicle_map();
  bad.speed_message = "NoSuchMessage";
  auto refused = VehicleCanSim::create(db, bad, config, circle);
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().message.find("NoSuchMessage"), std::string::npos)
      << refused.error().message;
}

}  // namespace
}  // namespace stac::sim
