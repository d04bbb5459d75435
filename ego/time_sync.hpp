// Which clock a scan's points are read in, against the pose clock (UTC, ns since 1970).
//
// Scan stamps come from the receiver (kernel or pcap time of the packets). The sensor's own
// clock is better when it is disciplined by GPS (PPS): its trailer gives microseconds past the
// hour, and the hour comes from
//   1. the INS's time (kInsHour) when a pose near the scan is known - robust, absolute;
//   2. else the status cycle's date and hour (kSensorUtc) - needs the NMEA input;
//   3. else (S2 without a GPS trailer, or no PPS: the sensor's clock free-runs) the receive
//      clock is used as it is (kReceive), which must then be the host's UTC (NTP/PTP).
#pragma once

#include <cstdint>
#include <optional>

#include "drivers/velodyne/model.hpp"
#include "drivers/velodyne/scan.hpp"

namespace stac::ego {

enum class ScanClockSource : std::uint8_t { kInsHour, kSensorUtc, kReceive };
const char* to_string(ScanClockSource s) noexcept;

struct ScanClock {
  std::int64_t scan_to_pose_ns = 0;  // add to the scan's stamps to get UTC
  ScanClockSource source = ScanClockSource::kReceive;
};

// `ins_utc_ns`: a UTC time from the INS within half an hour of the scan (e.g. the newest pose).
ScanClock scan_clock(const velodyne::ScanHeader& header, velodyne::TrailerKind trailer,
                     std::optional<std::int64_t> ins_utc_ns) noexcept;

}  // namespace stac::ego
