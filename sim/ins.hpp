// A virtual Applanix POS LV: the sim's ego trajectory as the Real-Time Data stream (port 5602):
// Group 1 (navigation solution) every 5 ms of GPS time, Groups 2 (RMS) and 3 (GNSS status) once
// per GPS second, each a complete "$GRP" message as drivers/applanix encodes it.
//
// Frames: the sim world is local ENU (x east, y north, z up, m) on the tangent plane of
// `origin` (GeographicLib::LocalCartesian, WGS84, ellipsoidal height); the ego reference point
// is reported with no lever arm. Attitude: the sim's R = Rz(yaw) Ry(pitch) Rx(roll) of the
// x-forward/y-left/z-up vehicle becomes Tate-Bryant roll/pitch/heading of the x-forward/
// y-right/z-down body in the NED at the fix (heading clockwise from north, pitch nose up
// positive, roll right side down positive), so ego::LocalFrame gives the sim's pose back.
// Rates and accelerations are of that body (deg/s, m/s^2, gravity removed), by central
// differences over +-50 ms (one-sided at sim time 0); velocity has no side slip (the speed along
// the yaw) plus the terrain's climb rate. Time: time1 = GPS seconds of the week (type 1), time2 =
// POS time (s since power-on); the distance tag is the path length travelled (type 1, POS).
// The Group 1 period must divide one second (Groups 2 and 3 follow the whole-second Group 1).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <span>

#include "drivers/applanix/groups.hpp"
#include "ego/local_frame.hpp"
#include "sim/lidar.hpp"

namespace stac::sim {

inline constexpr std::int64_t kGpsEpochUnixS = 315'964'800;  // 1980-01-06T00:00:00Z
inline constexpr int kGpsUtcLeapSeconds = 18;                // GPS - UTC since 2017 (still in 2026)

struct GpsTime {
  std::uint32_t week = 0;
  double seconds_of_week = 0.0;
};
// GPS nanoseconds since the GPS epoch of a UTC time (ns since the Unix epoch), and its week.
std::int64_t gps_ns_of_utc(std::int64_t utc_ns, int leap_s = kGpsUtcLeapSeconds) noexcept;
GpsTime gps_time_of_gps_ns(std::int64_t gps_ns) noexcept;

struct InsConfig {
  // The sim world's geodetic anchor (default: the real Applanix capture's last fix, Kingston ON).
  ego::Geodetic origin{44.2449408681, -76.5096210157, 77.0};
  std::int64_t start_ns = 0;                  // UTC of sim time 0 (ns since the Unix epoch)
  std::int64_t group1_period_ns = 5'000'000;  // 200 Hz, on multiples of GPS time
  double pos_time_at_start_s = 600.0;         // time2: the POS was switched on 10 min before
};

struct InsMessage {
  std::uint16_t group = 0;
  std::int64_t stamp_ns = 0;            // UTC ns: the solution's time (sent without latency)
  std::span<const std::uint8_t> bytes;  // valid until the next call to next()
};

class InsSim {
 public:
  using EgoFn = std::function<EgoState(double)>;  // sim time (s) -> ego state
  InsSim(const InsConfig& config, EgoFn ego);

  // UTC ns of the message next() gives next.
  std::int64_t next_stamp_ns() const noexcept;
  // The next message in time order: a Group 1, and after the Group 1 of a whole GPS second its
  // Group 2 and Group 3.
  InsMessage next();

  // The Group 1 content of sim time t (s), as next() encodes it.
  applanix::Group1 group1_at(double t) const;
  std::uint32_t gps_week() const noexcept { return start_gps_.week; }

 private:
  double sim_time(std::int64_t gps_ns) const noexcept;

  InsConfig config_;
  EgoFn ego_;
  GeographicLib::LocalCartesian frame_;
  std::int64_t start_gps_ns_ = 0;
  GpsTime start_gps_;
  std::int64_t sample_gps_ns_ = 0;  // GPS ns of the next Group 1
  int pending_ = 0;                 // 0: Group 1 next; 2 / 3: that group of the last second
  double distance_m_ = 0.0;         // distance tag: path length travelled
  double last_speed_ = 0.0;
  bool first_ = true;
  std::array<std::uint8_t, 1024> buffer_{};
};

}  // namespace stac::sim
