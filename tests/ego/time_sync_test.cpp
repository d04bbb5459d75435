#include "ego/time_sync.hpp"

#include <gtest/gtest.h>

namespace stac::ego {
namespace {

constexpr std::int64_t kHour18 = 1'795'456'800'000'000'000;  // 2026-11-23T18:00:00Z

// A scan whose first firing the sensor saw 0.25 s past 18:00 UTC (trailer 250000 us, firing
// 48 us into its packet) and the receiver stamped 2.5 s late on its own clock.
velodyne::ScanHeader header() {
  velodyne::ScanHeader h;
  h.device_usec_first = 250'000;
  h.first_firing_in_packet_ns = 48'000;
  h.stamp_ns = kHour18 + 250'048'000 + 2'500'000'000;
  h.gps = velodyne::GpsState::kPpsAndNmea;
  return h;
}

TEST(ScanClock, PpsSensorTakesItsHourFromTheInsAcrossTheTopOfTheHour) {
  // The INS's newest pose is still 17:59:59.9 UTC.
  const ScanClock c =
      scan_clock(header(), velodyne::TrailerKind::kGpsStatus, kHour18 - 100'000'000);
  EXPECT_EQ(c.source, ScanClockSource::kInsHour);
  EXPECT_EQ(header().stamp_ns + c.scan_to_pose_ns, kHour18 + 250'048'000);
}

TEST(ScanClock, WithoutInsTheStatusCycleDateServes) {
  velodyne::ScanHeader h = header();
  h.device_utc_ns = kHour18 + 250'048'000;
  const ScanClock c = scan_clock(h, velodyne::TrailerKind::kGpsStatus, std::nullopt);
  EXPECT_EQ(c.source, ScanClockSource::kSensorUtc);
  EXPECT_EQ(h.stamp_ns + c.scan_to_pose_ns, kHour18 + 250'048'000);
  h.device_utc_ns = 0;  // no valid cycle yet either
  EXPECT_EQ(scan_clock(h, velodyne::TrailerKind::kGpsStatus, std::nullopt).source,
            ScanClockSource::kReceive);
}

TEST(ScanClock, AFreeRunningSensorClockIsNeverUsed) {
  velodyne::ScanHeader h = header();
  h.gps = velodyne::GpsState::kNmeaOnly;  // no PPS: the microseconds drift
  const ScanClock c = scan_clock(h, velodyne::TrailerKind::kGpsStatus, kHour18);
  EXPECT_EQ(c.source, ScanClockSource::kReceive);
  EXPECT_EQ(c.scan_to_pose_ns, 0);
  EXPECT_EQ(scan_clock(header(), velodyne::TrailerKind::kSpinCount, kHour18).source,
            ScanClockSource::kReceive);  // the S2's trailer has no time
}

}  // namespace
}  // namespace stac::ego
