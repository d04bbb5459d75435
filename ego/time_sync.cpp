#include "ego/time_sync.hpp"

#include "drivers/velodyne/status.hpp"

namespace stac::ego {

const char* to_string(ScanClockSource s) noexcept {
  switch (s) {
    case ScanClockSource::kInsHour:
      return "sensor clock, hour from the INS";
    case ScanClockSource::kSensorUtc:
      return "sensor clock, hour from its status cycle";
    case ScanClockSource::kReceive:
      break;
  }
  return "receive clock";
}

ScanClock scan_clock(const velodyne::ScanHeader& header, velodyne::TrailerKind trailer,
                     std::optional<std::int64_t> ins_utc_ns) noexcept {
  const bool pps =
      header.gps == velodyne::GpsState::kPpsAndNmea || header.gps == velodyne::GpsState::kPpsOnly;
  if (trailer != velodyne::TrailerKind::kGpsStatus || !pps) return {};
  if (ins_utc_ns) {
    if (const auto packet = velodyne::resolve_past_hour_ns(header.device_usec_first, *ins_utc_ns)) {
      const std::int64_t first_firing = *packet + header.first_firing_in_packet_ns;
      return {first_firing - header.stamp_ns, ScanClockSource::kInsHour};
    }
  }
  if (header.device_utc_ns != 0) {
    return {header.device_utc_ns - header.stamp_ns, ScanClockSource::kSensorUtc};
  }
  return {};
}

}  // namespace stac::ego
