// A 360-degree scan: fixed-capacity storage of points plus what happened while it was framed.
#pragma once

#include <cstdint>
#include <span>

#include "drivers/velodyne/point.hpp"
#include "drivers/velodyne/status.hpp"
#include "rt/fixed_vector.hpp"

namespace stac::velodyne {

struct ScanHeader {
  std::uint64_t sequence = 0;       // 0, 1, 2, ... in the order scans were closed
  std::int64_t stamp_ns = 0;        // time of the scan's first firing (ns, source clock)
  std::int64_t end_stamp_ns = 0;    // time of its last firing
  std::uint16_t first_azimuth = 0;  // raw rotation of the first and last firing (0.01 deg)
  std::uint16_t last_azimuth = 0;
  std::uint32_t packets = 0;            // packets that contributed points
  std::uint32_t packets_lost = 0;       // estimated from azimuth steps larger than usual
  std::uint32_t late_firings = 0;       // reordered firings that arrived after their scan closed
  std::uint32_t points_dropped = 0;     // returns that did not fit the scan's capacity
  std::uint32_t device_usec_first = 0;  // trailer (microseconds past the hour) of the packet
                                        // holding the first firing
  std::int32_t first_firing_in_packet_ns = 0;  // the first firing's offset in that packet
  std::int64_t device_utc_ns = 0;     // UTC of the first firing by the sensor's clock, from the
                                      // trailer and the status cycle's date; 0 = unknown
  GpsState gps = GpsState::kUnknown;  // the sensor's GPS input when the scan opened
  bool starts_at_cut = false;         // opened by a cut-angle crossing (not by start-up or a gap)
  bool ends_at_cut = false;           // closed by a cut-angle crossing (not by a gap or timeout)
  bool dual_return = false;
  // Closed with more packets lost than ScanAssemblerConfig::min_completeness allows.
  bool below_completeness = false;
  // The fraction of its packets that arrived (1 when none is known lost).
  [[nodiscard]] double completeness() const noexcept {
    const double all = static_cast<double>(packets) + static_cast<double>(packets_lost);
    return all > 0 ? static_cast<double>(packets) / all : 1.0;
  }
  [[nodiscard]] bool complete() const noexcept {
    return starts_at_cut && ends_at_cut && points_dropped == 0 && !below_completeness;
  }
};

struct Scan {
  explicit Scan(std::size_t capacity) : points(capacity) {}
  ScanHeader header;
  rt::FixedVector<Point> points;
};

}  // namespace stac::velodyne
