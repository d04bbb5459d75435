#include "drivers/velodyne/status.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <numbers>
#include <random>
#include <string_view>
#include <vector>

#include "drivers/velodyne/scan_assembler.hpp"
#include "rt/testing/alloc_counter.hpp"
#include "shared_data.hpp"
#include "velodyne/synthetic_stream.hpp"

namespace stac::velodyne {
namespace {

using stac::testing::shared_data;

constexpr const char* kS3Yaml = "velodyne/calib/rosdrivers_64e_s3-xiesc.yaml";
constexpr const char* kS21Xml = "velodyne/calib/rosdrivers_64e_s2.1-sztaki_db.xml";
constexpr double kRadToDeg = 180.0 / std::numbers::pi;

SensorStatus example_status() {
  SensorStatus s;
  s.valid = true;
  s.time = {2026, 11, 23, 17, 42, 9};
  s.gps_raw = 'A';
  s.gps = GpsState::kPpsAndNmea;
  s.temperature_c = 41;
  s.firmware = 0x47;
  return s;
}

UnitParameters example_unit() {
  UnitParameters u;
  u.upper_noise_threshold = 24;
  u.lower_noise_threshold = 23;
  u.calibration_date = DateTime{2016, 11, 15, 12, 47, 47};
  u.humidity = 25;
  u.rpm = 600;
  u.fov_start = 0;
  u.fov_end = 36000;
  u.run_hours = 2685;
  u.ip_source = {192, 168, 3, 43};
  u.ip_destination = {192, 168, 3, 255};
  u.return_mode = ReturnMode::kStrongest;
  u.power_level = 0xA8;
  u.warnings = 0x60;  // PPS and GPS time present
  return u;
}

std::vector<StatusByte> sequence(Model model, const Calibration& c,
                                 const UnitParameters& unit = example_unit()) {
  std::vector<StatusByte> out(kStatusDumpPackets);
  auto ok = encode_status_sequence(model, example_status(), unit, c,
                                   std::span<StatusByte, kStatusDumpPackets>(out));
  EXPECT_TRUE(ok) << ok.error().message;
  return out;
}

void feed(StatusDecoder& d, const std::vector<StatusByte>& bytes, std::size_t from = 0,
          std::size_t to = kStatusDumpPackets) {
  for (std::size_t k = from; k < to; ++k) d.add(bytes[k].type, bytes[k].value);
}

// The dump quantises angles to 0.01 deg, lengths to 1 mm and the focal slope to 0.1.
void expect_same_within_quantisation(const Calibration& a, const Calibration& b) {
  ASSERT_EQ(a.num_lasers, b.num_lasers);
  for (int i = 0; i < a.num_lasers; ++i) {
    SCOPED_TRACE("laser " + std::to_string(i));
    const LaserCalibration& x = a.lasers[static_cast<std::size_t>(i)];
    const LaserCalibration& y = b.lasers[static_cast<std::size_t>(i)];
    EXPECT_EQ(x.laser_id, y.laser_id);
    EXPECT_NEAR(x.vert_correction_rad * kRadToDeg, y.vert_correction_rad * kRadToDeg, 0.005 + 1e-9);
    EXPECT_NEAR(x.rot_correction_rad * kRadToDeg, y.rot_correction_rad * kRadToDeg, 0.005 + 1e-9);
    EXPECT_NEAR(x.dist_correction_m, y.dist_correction_m, 0.0005 + 1e-9);
    EXPECT_NEAR(x.dist_correction_x_m, y.dist_correction_x_m, 0.0005 + 1e-9);
    EXPECT_NEAR(x.dist_correction_y_m, y.dist_correction_y_m, 0.0005 + 1e-9);
    EXPECT_NEAR(x.vert_offset_m, y.vert_offset_m, 0.0005 + 1e-9);
    EXPECT_NEAR(x.horiz_offset_m, y.horiz_offset_m, 0.0005 + 1e-9);
    EXPECT_NEAR(x.focal_distance_m, y.focal_distance_m, 0.0005 + 1e-9);
    EXPECT_NEAR(x.focal_slope, y.focal_slope, 0.05 + 1e-9);
    EXPECT_EQ(x.min_intensity, y.min_intensity);
    EXPECT_EQ(x.max_intensity, y.max_intensity);
    EXPECT_EQ(x.two_pt_correction_available, y.two_pt_correction_available);
  }
}

// The real S3 calibration (unit #1090) and the 4160 status bytes that carry it.
class RealS3Dump : public ::testing::Test {
 protected:
  void SetUp() override {
    STAC_REQUIRE_SHARED_DATA(kS3Yaml);
    auto loaded = load_calibration(shared_data(kS3Yaml));
    ASSERT_TRUE(loaded) << loaded.error().message;
    file = *loaded;
    bytes = sequence(Model::kS3, file);
  }
  Calibration file;
  std::vector<StatusByte> bytes;
};

TEST(StatusCrc, MatchesTheCrc16Check) {
  // CRC-16 poly 0x8005, init 0, unreflected ("CRC-16/UMTS"): check value of "123456789".
  constexpr std::string_view text = "123456789";
  const std::vector<std::uint8_t> bytes(text.begin(), text.end());
  EXPECT_EQ(crc16_8005(bytes), 0xFEE8);
  EXPECT_EQ(crc16_8005({}), 0);
}

TEST_F(RealS3Dump, CalibrationRoundTripsThroughTheDumpWithCrc) {
  StatusDecoder d(Model::kS3);
  EXPECT_FALSE(d.has_calibration());
  EXPECT_FALSE(d.calibration());
  feed(d, bytes);
  ASSERT_TRUE(d.has_calibration());
  auto stream = d.calibration();
  ASSERT_TRUE(stream) << stream.error().message;
  EXPECT_EQ(stream->source, "status stream");
  expect_same_within_quantisation(file, *stream);
  EXPECT_TRUE(d.unit().crc_checked);
  EXPECT_EQ(d.counters().dumps, 1u);
  EXPECT_EQ(d.counters().cycles, 260u);
  EXPECT_EQ(d.counters().out_of_sequence, 0u);
}

TEST(StatusDecoder, RealS21CalibrationRoundTripsWithTheLengthChecksum) {
  STAC_REQUIRE_SHARED_DATA(kS21Xml);
  auto file = load_calibration(shared_data(kS21Xml));
  ASSERT_TRUE(file) << file.error().message;
  StatusDecoder d(Model::kS2_1);
  const auto bytes = sequence(Model::kS2_1, *file);
  feed(d, bytes);
  // Issue 31: the S2.1 has no CRC, so one dump alone is not used; the next, identical, confirms.
  EXPECT_FALSE(d.has_calibration());
  EXPECT_EQ(d.counters().unconfirmed, 1u);
  feed(d, bytes);
  auto stream = d.calibration();
  ASSERT_TRUE(stream) << stream.error().message;
  expect_same_within_quantisation(*file, *stream);
  EXPECT_FALSE(d.unit().crc_checked);  // the S2.1 writes 1820 where the S3 writes its CRC
}

TEST(StatusDecoder, AFlippedBitInAnS21DumpIsNeverUsed) {
  STAC_REQUIRE_SHARED_DATA(kS21Xml);
  auto file = load_calibration(shared_data(kS21Xml));
  ASSERT_TRUE(file) << file.error().message;
  const auto good = sequence(Model::kS2_1, *file);
  LaserCalibration& l = file->lasers[7];
  l.rot_correction_rad += 0.001;  // a different value where a flipped bit would be
  const auto other = sequence(Model::kS2_1, *file);
  StatusDecoder d(Model::kS2_1);
  feed(d, good);
  feed(d, other);  // differs from the one before: neither is used
  EXPECT_FALSE(d.has_calibration());
  EXPECT_EQ(d.counters().unconfirmed, 2u);
  feed(d, other);  // the same twice: used
  ASSERT_TRUE(d.has_calibration());
}

TEST_F(RealS3Dump, DecodesTimeGpsTemperatureFirmwareAndUnitParameters) {
  StatusDecoder d(Model::kS3);
  feed(d, bytes, 0, 9);  // one H..V run is enough for the sensor status
  const SensorStatus& s = d.sensor();
  ASSERT_TRUE(s.valid);
  EXPECT_EQ(s.time.year, 2026);
  EXPECT_EQ(s.time.month, 11);
  EXPECT_EQ(s.time.day, 23);
  EXPECT_EQ(s.time.hour, 17);
  EXPECT_EQ(s.time.minute, 42);
  EXPECT_EQ(s.time.second, 9);
  EXPECT_EQ(s.gps, GpsState::kPpsAndNmea);
  EXPECT_EQ(s.temperature_c, 41);
  EXPECT_EQ(s.firmware, 0x47);

  feed(d, bytes, 9);
  const UnitParameters& u = d.unit();
  const UnitParameters e = example_unit();
  EXPECT_EQ(u.upper_noise_threshold, e.upper_noise_threshold);
  EXPECT_EQ(u.lower_noise_threshold, e.lower_noise_threshold);
  ASSERT_TRUE(u.calibration_date);
  EXPECT_EQ(u.calibration_date->year, 2016);
  EXPECT_EQ(u.calibration_date->second, 47);
  EXPECT_EQ(u.humidity, 25);
  EXPECT_EQ(u.rpm, 600);
  EXPECT_EQ(u.fov_end, 36000);
  EXPECT_EQ(u.run_hours, 2685);
  EXPECT_EQ(u.ip_source, e.ip_source);
  EXPECT_EQ(u.ip_destination, e.ip_destination);
  EXPECT_EQ(u.return_mode, ReturnMode::kStrongest);
  EXPECT_EQ(u.power_level, 0xA8);
  EXPECT_EQ(u.warnings, 0x60);  // from the S3's 'W' bytes
}

TEST_F(RealS3Dump, DualReturnModeAndUnsetCalibrationDate) {
  UnitParameters unit = example_unit();
  unit.return_mode = ReturnMode::kDual;
  unit.calibration_date.reset();  // sent as 0xFF bytes
  StatusDecoder d(Model::kS3);
  feed(d, sequence(Model::kS3, file, unit));
  ASSERT_TRUE(d.has_calibration());
  EXPECT_EQ(d.unit().return_mode, ReturnMode::kDual);
  EXPECT_FALSE(d.unit().calibration_date);
}

TEST_F(RealS3Dump, LostPacketDropsTheDumpAndTheNextUnbrokenOneIsAccepted) {
  StatusDecoder d(Model::kS3);
  feed(d, bytes, 0, 2000);
  feed(d, bytes, 2001);  // packet 2000 lost
  EXPECT_FALSE(d.has_calibration());
  EXPECT_EQ(d.counters().dumps_broken, 1u);
  EXPECT_GE(d.counters().out_of_sequence, 1u);
  auto err = d.calibration();
  ASSERT_FALSE(err);
  EXPECT_NE(err.error().message.find("unbroken"), std::string::npos) << err.error().message;
  feed(d, bytes);
  EXPECT_TRUE(d.has_calibration());
  EXPECT_EQ(d.counters().dumps, 1u);
}

TEST_F(RealS3Dump, StartingInTheMiddleWaitsForTheNextUnitMarker) {
  StatusDecoder d(Model::kS3);
  feed(d, bytes, 1003);  // joins mid-cycle, mid-dump
  EXPECT_FALSE(d.has_calibration());
  EXPECT_EQ(d.counters().bad_layout + d.counters().bad_checksum, 0u);
  EXPECT_TRUE(d.sensor().valid);
  feed(d, bytes);  // the sensor repeats the dump
  EXPECT_TRUE(d.has_calibration());
}

TEST_F(RealS3Dump, CorruptedLaserByteFailsTheS3Crc) {
  // Cycle 10 (laser 2, part 1), data byte 3: a correction byte.
  bytes[10 * kStatusCyclePackets + kStatusTypedBytes + 3].value ^= 0x10;
  StatusDecoder d(Model::kS3);
  feed(d, bytes);
  EXPECT_FALSE(d.has_calibration());
  EXPECT_EQ(d.counters().bad_checksum, 1u);
}

TEST_F(RealS3Dump, GarbageTrailersNeverYieldACalibration) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> byte(0, 255);
  StatusDecoder d(Model::kS3);
  for (int i = 0; i < 100'000; ++i) {
    d.add(static_cast<std::uint8_t>(byte(rng)), static_cast<std::uint8_t>(byte(rng)));
  }
  EXPECT_FALSE(d.has_calibration());
  EXPECT_EQ(d.counters().packets, 100'000u);
  feed(d, bytes);  // and it recovers when real bytes come
  EXPECT_TRUE(d.has_calibration());
}

TEST(StatusDecoder, EncodingRefusesValuesThatDoNotFitNamingLaserAndField) {
  Calibration c;
  c.source = "test.yaml";
  c.lasers[5].dist_correction_m = 40.0;  // 40000 mm > 32767
  std::vector<StatusByte> out(kStatusDumpPackets);
  auto r = encode_status_sequence(Model::kS3, example_status(), example_unit(), c,
                                  std::span<StatusByte, kStatusDumpPackets>(out));
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("laser 5"), std::string::npos) << r.error().message;
  EXPECT_NE(r.error().message.find("dist_correction"), std::string::npos) << r.error().message;
}

TEST(StatusTime, UtcFromMicrosecondsPastTheHour) {
  SensorStatus s = example_status();           // 2026-11-23 17:42:09
  const std::int64_t hour_17 = 1'795'453'200;  // 2026-11-23T17:00:00Z (date -u -d ... +%s)
  auto t = utc_time_ns(s, 2'529'250'000U);     // 42 min 9.25 s
  ASSERT_TRUE(t);
  EXPECT_EQ(*t, hour_17 * 1'000'000'000 + 2'529'250'000'000);
  s.valid = false;
  EXPECT_FALSE(utc_time_ns(s, 0));
  s.valid = true;
  EXPECT_FALSE(utc_time_ns(s, 3'600'000'000U));  // not a time past the hour
}

TEST(StatusTime, TopOfHourRolloverBetweenCycleAndPacket) {
  SensorStatus s = example_status();
  s.time = {2026, 12, 31, 23, 59, 59};  // the last cycle said 23:59:59 on new year's eve
  auto t = utc_time_ns(s, 100'000U);    // the packet is 0.1 s past the next hour
  ASSERT_TRUE(t);
  const std::int64_t new_year_2027 = 1'798'761'600;  // 2027-01-01T00:00:00Z
  EXPECT_EQ(*t, new_year_2027 * 1'000'000'000 + 100'000'000);

  s.time = {2027, 1, 1, 0, 0, 0};           // the cycle is already in the new hour,
  auto u = utc_time_ns(s, 3'599'990'000U);  // the packet 10 ms before it
  ASSERT_TRUE(u);
  EXPECT_EQ(*u, new_year_2027 * 1'000'000'000 - 10'000'000);
}

TEST_F(RealS3Dump, DecodesWholeDumpsWithoutAllocating) {
  static_assert(noexcept(std::declval<StatusDecoder&>().add(0, 0)));
  static_assert(noexcept(utc_time_ns(SensorStatus{}, 0U)));
  StatusDecoder d(Model::kS3);
  stac::rt::testing::AllocationCounter counter;
  for (int run = 0; run < 3; ++run) feed(d, bytes);
  counter.stop();
  EXPECT_EQ(d.counters().dumps, 3u);
  EXPECT_EQ(counter.allocations(), 0u);
}

TEST(StatusTime, PastHourResolvesAgainstAnyReferenceClock) {
  const std::int64_t h = 1'795'453'200'000'000'000;  // 2026-11-23T17:00:00Z
  // An INS says 17:59:59.9; the sensor's trailer already says 0.2 s past the hour.
  EXPECT_EQ(resolve_past_hour_ns(200'000U, h + 3'599'900'000'000), h + 3'600'200'000'000);
  // The INS already says 18:00:00.1; the trailer is still 17:59:59.95.
  EXPECT_EQ(resolve_past_hour_ns(3'599'950'000U, h + 3'600'100'000'000), h + 3'599'950'000'000);
  EXPECT_EQ(resolve_past_hour_ns(1'000'000U, h + 1'000'000'000), h + 1'000'000'000);
  EXPECT_FALSE(resolve_past_hour_ns(3'600'000'000U, h));
}

TEST(StatusTime, CalendarOfUtcNanoseconds) {
  const DateTime t = utc_date_time(1'798'761'599'500'000'000);  // 2026-12-31T23:59:59.5Z
  EXPECT_EQ(t.year, 2026);
  EXPECT_EQ(t.month, 12);
  EXPECT_EQ(t.day, 31);
  EXPECT_EQ(t.hour, 23);
  EXPECT_EQ(t.minute, 59);
  EXPECT_EQ(t.second, 59);
  const DateTime leap = utc_date_time(1'709'164'800'000'000'000);  // 2024-02-29T00:00:00Z
  EXPECT_EQ(leap.month, 2);
  EXPECT_EQ(leap.day, 29);
}

TEST(StatusTrailerWriter, ScanHeadersCarryUtcAndGpsStateAndTheCalibrationArrives) {
  const Calibration flat = stac::testing::flat_calibration();
  SensorStatus sensor = example_status();
  auto writer = StatusTrailerWriter::create(Model::kS2_1, sensor, example_unit(), flat);
  ASSERT_TRUE(writer) << writer.error().message;
  stac::testing::StreamSpec spec;
  spec.seconds = 2.8;  // more than two 4160-packet dumps (an S2.1 dump is used once confirmed)
  spec.start_ns = 1'795'453'200'000'000'000 + 3'599'500'000'000;  // 0.5 s before 18:00 UTC
  auto packets = stac::testing::make_stream(spec);
  ScanAssemblerConfig config;
  config.decoder.model = Model::kS2_1;
  ScanAssembler assembler(flat, config);
  Scan scan(scan_capacity(config));
  assembler.begin(scan);
  int checked = 0;
  for (auto& p : packets) {
    writer->write(p.bytes.data() + kPacketSize - 6, p.stamp_ns);
    if (!assembler.add_packet(p.bytes, p.stamp_ns)) continue;
    if (scan.header.device_utc_ns != 0) {
      // The first firing's UTC, across the top of the hour, from the trailer and the cycle
      // (the trailer has whole microseconds).
      EXPECT_LT(std::llabs(scan.header.device_utc_ns - scan.header.stamp_ns), 1000)
          << scan.header.device_utc_ns << " vs " << scan.header.stamp_ns;
      EXPECT_EQ(scan.header.gps, GpsState::kPpsAndNmea);
      ++checked;
    }
    assembler.begin(scan);
  }
  EXPECT_GE(checked, 10);
  EXPECT_TRUE(assembler.status().has_calibration());
  EXPECT_EQ(assembler.status().counters().out_of_sequence, 0u);
  auto stream = assembler.status().calibration();
  ASSERT_TRUE(stream) << stream.error().message;
  expect_same_within_quantisation(flat, *stream);
}

}  // namespace
}  // namespace stac::velodyne
