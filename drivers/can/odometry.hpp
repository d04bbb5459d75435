// Vehicle odometry from CAN: speed and yaw rate decoded through a DBC signal map, and a 2D
// dead-reckoning integrator the pose history can fall back on when the INS is lost.
//
// Units and conventions: speed in m/s (the DBC signal may be in km/h or m/s; km/h is converted),
// yaw rate in deg/s (DBC "deg/s" or "rad/s"), positive counter-clockwise seen from above (a left
// turn; ISO 8855, z up) after the configured sign. Dead-reckoning frame: x forward and y left at
// the start (or at the pose given to reset()), yaw counter-clockwise in radians.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "drivers/can/dbc.hpp"
#include "drivers/can/frame.hpp"
#include "drivers/can/socketcan.hpp"
#include "rt/expected.hpp"

namespace stac::can {

// Which DBC signal carries what (config/stac.yaml `can:`).
struct OdometrySignalMap {
  std::string speed_message;
  std::string speed_signal;
  std::string yaw_rate_message;
  std::string yaw_rate_signal;
  double yaw_rate_sign = 1.0;  // -1 when the vehicle reports positive to the right
};

// One frame's contribution; neither flag set when the frame carries neither signal.
struct OdometryUpdate {
  std::int64_t stamp_ns = 0;
  bool has_speed = false;
  bool has_yaw_rate = false;
  double speed_mps = 0.0;
  double yaw_rate_dps = 0.0;
};

struct OdometryDecoderCounters {
  std::uint64_t frames = 0;        // frames offered
  std::uint64_t decoded = 0;       // frames that carried speed or yaw rate
  std::uint64_t not_mapped = 0;    // ids outside the signal map: dropped here (SocketCAN's kernel
                                   // filter drops them before; gs_usb delivers the whole bus)
  std::uint64_t short_frames = 0;  // the right id but fewer bytes than the signal needs: dropped
  std::uint64_t remote_or_error = 0;  // remote and error frames with a mapped id: ignored
  // A speed over 200 m/s or a yaw rate over 720 deg/s in magnitude, or not a number: dropped.
  std::uint64_t implausible = 0;
};

class OdometryDecoder {
 public:
  // Errors name the missing message or signal, a multiplexed signal, or a unit that is not
  // km/h, m/s (speed) or deg/s, rad/s (yaw rate).
  static rt::Result<OdometryDecoder> create(const Database& db, const OdometrySignalMap& map);

  // No allocation, no I/O.
  OdometryUpdate decode(const Frame& frame) noexcept;
  const OdometryDecoderCounters& counters() const noexcept { return counters_; }
  // The ids to let through a SocketCAN kernel filter (one, or two when the signals differ).
  std::vector<CanIdFilter> filters() const;

  struct Channel {
    Signal signal;
    std::uint32_t id = 0;
    bool extended = false;
    double scale = 1.0;  // to m/s or deg/s, including the sign
  };
  const Channel& speed() const noexcept { return speed_; }
  const Channel& yaw_rate() const noexcept { return yaw_rate_; }

 private:
  Channel speed_;
  Channel yaw_rate_;
  OdometryDecoderCounters counters_;
};

struct Pose2 {
  std::int64_t stamp_ns = 0;
  double x_m = 0.0;
  double y_m = 0.0;
  double yaw_rad = 0.0;  // counter-clockwise, wrapped to (-pi, pi]
};

enum class DeadReckoningStatus : std::uint8_t {
  kNoInput,  // speed or yaw rate never received since reset()
  kOk,       // both received within the stale timeout of the time asked about
  kStale,    // one of them is older than the stale timeout
};
const char* to_string(DeadReckoningStatus status) noexcept;

struct DeadReckoningConfig {
  std::int64_t stale_timeout_ns = 200'000'000;  // an input older than this makes the pose stale
};

// Integrates speed and yaw rate into a 2D pose. Between two samples of an input its value is the
// mean of both (midpoint rule); the motion over each interval is the exact circular arc for that
// speed and yaw rate (a straight line when the yaw rate is ~0). Gaps longer than the stale timeout
// are not integrated (counted in gaps()): the pose is stale until both inputs are fresh again.
class DeadReckoning {
 public:
  explicit DeadReckoning(DeadReckoningConfig config) noexcept : config_(config) {}

  // Starts over from `pose` (e.g. the last INS pose); inputs are forgotten.
  void reset(const Pose2& pose) noexcept;
  // Feeds one update; updates older than the current pose time are ignored (counted).
  void update(const OdometryUpdate& u) noexcept;

  const Pose2& pose() const noexcept { return pose_; }  // at the last update's time
  DeadReckoningStatus status(std::int64_t now_ns) const noexcept;
  std::uint64_t gaps() const noexcept { return gaps_; }
  std::uint64_t out_of_order() const noexcept { return out_of_order_; }

 private:
  void integrate(std::int64_t t_ns, double speed_mps, double yaw_rate_dps) noexcept;

  DeadReckoningConfig config_;
  Pose2 pose_;
  bool started_ = false;  // pose_.stamp_ns is meaningful
  bool have_speed_ = false;
  bool have_yaw_rate_ = false;
  double speed_mps_ = 0.0;
  double yaw_rate_dps_ = 0.0;
  std::int64_t speed_stamp_ns_ = 0;
  std::int64_t yaw_rate_stamp_ns_ = 0;
  std::uint64_t gaps_ = 0;
  std::uint64_t out_of_order_ = 0;
};

}  // namespace stac::can
