#include "drivers/can/odometry.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "rt/testing/alloc_counter.hpp"
#include "test_paths.hpp"

namespace stac::can {
namespace {

Database shipped_dbc() {
  auto db =
      load_dbc(std::filesystem::path(::stac::testing::source_dir()) / "config/can/vehicle.dbc");
  EXPECT_TRUE(db) << db.error().message;
  return std::move(db).value();
}

OdometrySignalMap shipped_map() {
  return {"WheelSpeeds", "VehicleSpeed", "YawRate", "YawRate", 1.0};
}

Frame frame(std::uint32_t id, std::initializer_list<std::uint8_t> bytes,
            std::int64_t stamp_ns = 0) {
  Frame f;
  f.id = id;
  f.stamp_ns = stamp_ns;
  for (const std::uint8_t b : bytes) f.data[f.dlc++] = b;
  return f;
}

TEST(OdometryDecoder, DecodesHandMadeFramesOfTheShippedDbc) {
  const Database db = shipped_dbc();
  auto d = OdometryDecoder::create(db, shipped_map());
  ASSERT_TRUE(d) << d.error().message;
  // 36.00 km/h = raw 3600 = 0x0E10, Motorola: high byte first -> 10 m/s.
  const auto s = d->decode(frame(0x1A0, {0x0E, 0x10, 0, 0, 0, 0, 0, 0}, 5));
  EXPECT_TRUE(s.has_speed);
  EXPECT_FALSE(s.has_yaw_rate);
  EXPECT_NEAR(s.speed_mps, 10.0, 1e-12);
  EXPECT_EQ(s.stamp_ns, 5);
  // -2.57 deg/s = raw -257 = 0xFEFF, Intel: low byte first.
  const auto y = d->decode(frame(0x1B0, {0xFF, 0xFE, 0, 0, 0, 0, 0, 0}));
  EXPECT_TRUE(y.has_yaw_rate);
  EXPECT_NEAR(y.yaw_rate_dps, -2.57, 1e-12);
  const auto other = d->decode(frame(0x123, {1, 2, 3}));
  EXPECT_FALSE(other.has_speed || other.has_yaw_rate);
  Frame ext = frame(0x1A0, {0x0E, 0x10, 0, 0, 0, 0, 0, 0});
  ext.extended = true;  // the same number as a 29-bit id is another message
  EXPECT_FALSE(d->decode(ext).has_speed);
  EXPECT_EQ(d->counters().frames, 4u);
  EXPECT_EQ(d->counters().decoded, 2u);
  EXPECT_EQ(d->counters().not_mapped, 2u);  // 0x123 and the 29-bit 0x1A0: dropped, counted
  const auto filters = d->filters();        // what a SocketCAN reader lets through
  ASSERT_EQ(filters.size(), 2u);
  EXPECT_EQ(filters[0].id, 0x1A0u);
  EXPECT_EQ(filters[1].id, 0x1B0u);
  EXPECT_FALSE(filters[0].extended || filters[1].extended);
}

TEST(OdometryDecoder, ShortAndRemoteFramesAreCountedNotDecoded) {
  const Database db = shipped_dbc();
  auto d = OdometryDecoder::create(db, shipped_map());
  ASSERT_TRUE(d);
  EXPECT_FALSE(d->decode(frame(0x1A0, {0x0E})).has_speed);  // speed needs 2 bytes
  Frame rtr = frame(0x1B0, {});
  rtr.remote = true;
  EXPECT_FALSE(d->decode(rtr).has_yaw_rate);
  EXPECT_EQ(d->counters().short_frames, 1u);
  EXPECT_EQ(d->counters().remote_or_error, 1u);
  EXPECT_EQ(d->counters().not_mapped, 0u);  // mapped ids, however bad the frames
}

// Issue 31: a value no vehicle has (here a map scaling 10 m/s to 1000 m/s) is dropped and
// counted, never integrated as "ok".
TEST(OdometryDecoder, ImplausibleSpeedsAreDroppedAndCounted) {
  // A speed in m/s with a factor of 1: raw 3600 is 3600 m/s.
  auto db = parse_dbc(
      "BO_ 416 WheelSpeeds: 8 X\n SG_ VehicleSpeed : 7|16@0+ (1,0) [0|65535] \"m/s\" X\n"
      "BO_ 432 Yaw: 8 X\n SG_ YawRate : 0|16@1- (1,0) [-32768|32767] \"deg/s\" X\n",
      "test.dbc");
  ASSERT_TRUE(db) << db.error().message;
  auto d = OdometryDecoder::create(*db, {"WheelSpeeds", "VehicleSpeed", "Yaw", "YawRate", 1.0});
  ASSERT_TRUE(d) << d.error().message;
  const auto s = d->decode(frame(0x1A0, {0x0E, 0x10, 0, 0, 0, 0, 0, 0}));
  EXPECT_FALSE(s.has_speed);
  EXPECT_EQ(d->counters().implausible, 1u);
  EXPECT_EQ(d->counters().decoded, 0u);
}

TEST(OdometryDecoder, SignAndUnitConversionsFromTheMap) {
  const auto db = parse_dbc(R"(BO_ 1 M: 8 X
 SG_ V : 0|16@1+ (0.01,0) [0|0] "m/s" X
 SG_ W : 16|16@1- (0.001,0) [0|0] "rad/s" X
 SG_ T : 32|8@1+ (1,0) [0|0] "degC" X
)",
                            "t.dbc");
  ASSERT_TRUE(db) << db.error().message;
  auto d = OdometryDecoder::create(*db, {"M", "V", "M", "W", -1.0});
  ASSERT_TRUE(d) << d.error().message;
  Frame f = frame(1, {0xE8, 0x03, 0xE8, 0x03, 0, 0, 0, 0});  // V = 10.00 m/s, W = 1.000 rad/s
  const auto u = d->decode(f);
  ASSERT_TRUE(u.has_speed && u.has_yaw_rate);  // one frame can carry both
  EXPECT_NEAR(u.speed_mps, 10.0, 1e-12);
  EXPECT_NEAR(u.yaw_rate_dps, -180.0 / std::numbers::pi, 1e-9);
  EXPECT_EQ(d->filters().size(), 1u);  // both signals in one message: one filter
  const auto bad_unit = OdometryDecoder::create(*db, {"M", "T", "M", "W", 1.0});
  ASSERT_FALSE(bad_unit);
  EXPECT_NE(bad_unit.error().message.find("unit 'degC'; expected km/h or m/s"), std::string::npos);
  const auto no_msg = OdometryDecoder::create(*db, {"Nope", "V", "M", "W", 1.0});
  ASSERT_FALSE(no_msg);
  EXPECT_NE(no_msg.error().message.find("no message 'Nope'"), std::string::npos);
  const auto no_sig = OdometryDecoder::create(*db, {"M", "V", "M", "Nope", 1.0});
  ASSERT_FALSE(no_sig);
  EXPECT_NE(no_sig.error().message.find("has no signal 'Nope'"), std::string::npos);
}

// Issue 47: a garbage DBC was reported as a missing message, without the file's name.
TEST(OdometryDecoder, AFileWithoutMessagesIsNamedAndCalledSo) {
  const auto db = parse_dbc("this is not a DBC file\n\x01\x02 at all\n", "odometry.dbc");
  ASSERT_TRUE(db) << db.error().message;
  const auto d = OdometryDecoder::create(*db, {"M", "V", "M", "W", 1.0});
  ASSERT_FALSE(d);
  EXPECT_NE(d.error().message.find("odometry.dbc: speed: no message 'M'"), std::string::npos)
      << d.error().message;
  EXPECT_NE(d.error().message.find("it holds no message at all"), std::string::npos)
      << d.error().message;
}

TEST(OdometryDecoder, DecodingAllocatesNothing) {
  static_assert(noexcept(std::declval<OdometryDecoder&>().decode(Frame{})));
  const Database db = shipped_dbc();
  auto d = OdometryDecoder::create(db, shipped_map());
  ASSERT_TRUE(d);
  const Frame f = frame(0x1A0, {0x0E, 0x10, 0, 0, 0, 0, 0, 0});
  double sum = 0;
  rt::testing::AllocationCounter counter;
  for (int i = 0; i < 1000; ++i) sum += d->decode(f).speed_mps;
  counter.stop();
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_NEAR(sum, 10000.0, 1e-6);
}

OdometryUpdate speed(std::int64_t t, double v) {
  return {t, true, false, v, 0.0};
}
OdometryUpdate yaw(std::int64_t t, double w) {
  return {t, false, true, 0.0, w};
}

constexpr std::int64_t kMs = 1'000'000;

// Speed and yaw rate at 100 Hz each, interleaved 5 ms apart, as two CAN messages would be.
void drive(DeadReckoning& dr, double v_mps, double w_dps, std::int64_t from_ns, double seconds) {
  const auto steps = static_cast<std::int64_t>(std::llround(seconds * 100));
  for (std::int64_t i = 0; i <= steps; ++i) {
    dr.update(speed(from_ns + i * 10 * kMs, v_mps));
    if (i < steps) dr.update(yaw(from_ns + i * 10 * kMs + 5 * kMs, w_dps));
  }
}

TEST(DeadReckoning, ConstantTurnClosesACircleOfRadiusSpeedOverYawRate) {
  DeadReckoning dr({200 * kMs});
  // 10 m/s at 36 deg/s: a full circle in 10 s, radius 10 / (0.2 pi) = 15.915 m, centre (0, R).
  const double radius = 10.0 / (36.0 * std::numbers::pi / 180.0);
  dr.update(yaw(0, 36.0));
  drive(dr, 10.0, 36.0, 0, 5.0);  // half way round
  EXPECT_NEAR(dr.pose().x_m, 0.0, 0.05);
  EXPECT_NEAR(dr.pose().y_m, 2 * radius, 0.05);
  EXPECT_NEAR(std::abs(dr.pose().yaw_rad), std::numbers::pi, 1e-3);
  drive(dr, 10.0, 36.0, 5000 * kMs, 5.0);
  EXPECT_NEAR(dr.pose().x_m, 0.0, 0.05);
  EXPECT_NEAR(dr.pose().y_m, 0.0, 0.05);
  EXPECT_NEAR(dr.pose().yaw_rad, 0.0, 1e-3);
  EXPECT_EQ(dr.status(10000 * kMs), DeadReckoningStatus::kOk);
  EXPECT_EQ(dr.gaps(), 0u);
}

TEST(DeadReckoning, StraightLineAlongTheStartHeading) {
  DeadReckoning dr({200 * kMs});
  dr.reset({0, 100.0, -20.0, std::numbers::pi / 2});  // seeded from an INS pose, facing +y
  dr.update(yaw(0, 0.0));
  drive(dr, 20.0, 0.0, 0, 3.0);
  EXPECT_NEAR(dr.pose().x_m, 100.0, 1e-9);
  EXPECT_NEAR(dr.pose().y_m, 40.0, 1e-9);
  EXPECT_NEAR(dr.pose().yaw_rad, std::numbers::pi / 2, 1e-12);
}

TEST(DeadReckoning, MidpointRuleFollowsALinearSpeedRamp) {
  DeadReckoning dr({200 * kMs});
  dr.update(yaw(0, 0.0));
  // speed 0 -> 10 m/s over 2 s at 100 Hz, yaw rate kept fresh: distance = 10 m exactly.
  for (int i = 0; i <= 200; ++i) {
    dr.update(speed(i * 10 * kMs, 0.05 * i));
    dr.update(yaw(i * 10 * kMs, 0.0));
  }
  EXPECT_NEAR(dr.pose().x_m, 10.0, 1e-9);
}

TEST(DeadReckoning, StatusGoesStaleAndGapsAreNotIntegrated) {
  DeadReckoning dr({200 * kMs});
  EXPECT_EQ(dr.status(0), DeadReckoningStatus::kNoInput);
  dr.update(speed(0, 10.0));
  EXPECT_EQ(dr.status(0), DeadReckoningStatus::kNoInput);  // no yaw rate yet
  dr.update(yaw(0, 0.0));
  EXPECT_EQ(dr.status(200 * kMs), DeadReckoningStatus::kOk);
  EXPECT_EQ(dr.status(201 * kMs), DeadReckoningStatus::kStale);
  // the yaw rate stops; speed goes on: nothing is integrated past the timeout
  for (int i = 1; i <= 100; ++i) dr.update(speed(i * 10 * kMs, 10.0));
  EXPECT_EQ(dr.status(1000 * kMs), DeadReckoningStatus::kStale);
  EXPECT_NEAR(dr.pose().x_m, 2.0, 1e-9);  // the first 200 ms at 10 m/s only
  EXPECT_EQ(dr.gaps(), 80u);
  dr.update(yaw(1005 * kMs, 0.0));  // back: fresh again
  EXPECT_EQ(dr.status(1005 * kMs), DeadReckoningStatus::kOk);
  dr.update(speed(1010 * kMs, 10.0));
  EXPECT_NEAR(dr.pose().x_m, 2.05, 1e-9);
  dr.update(speed(500 * kMs, 10.0));  // from the past: ignored
  EXPECT_EQ(dr.out_of_order(), 1u);
  EXPECT_STREQ(to_string(DeadReckoningStatus::kStale), "stale");
}

}  // namespace
}  // namespace stac::can
