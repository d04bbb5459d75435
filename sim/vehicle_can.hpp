// A virtual vehicle CAN bus: the ego's speed and yaw rate as the frames of a DBC signal map
// (config/stac.yaml `can:`), periodic like a vehicle's ECUs send them. Values are encoded
// through the DBC (so quantised by its factors), in the signal's unit (km/h or m/s, deg/s or
// rad/s) and sign convention, exactly the inverse of can::OdometryDecoder. Other signals of the
// messages are left zero. When speed and yaw rate share a message, it is sent at the faster rate.
#pragma once

#include <cstdint>
#include <functional>

#include "drivers/can/dbc.hpp"
#include "drivers/can/frame.hpp"
#include "drivers/can/odometry.hpp"
#include "rt/expected.hpp"
#include "sim/lidar.hpp"

namespace stac::sim {

struct VehicleCanConfig {
  std::int64_t start_ns = 0;        // UTC of sim time 0 (ns since the Unix epoch)
  double speed_rate_hz = 50.0;      // wheel-speed message
  double yaw_rate_rate_hz = 100.0;  // yaw-rate sensor message
  double speed_phase_s = 0.0013;    // first frame after start: ECUs are not in phase
  double yaw_rate_phase_s = 0.0007;
};

struct VehicleCanCounters {
  std::uint64_t frames = 0;
  std::uint64_t unencodable = 0;  // a value outside its signal's range: frame not sent
};

class VehicleCanSim {
 public:
  using EgoFn = std::function<EgoState(double)>;
  // Fails when the map does not fit the DBC (as OdometryDecoder::create) or a rate is not positive.
  static rt::Result<VehicleCanSim> create(const can::Database& db,
                                          const can::OdometrySignalMap& map,
                                          const VehicleCanConfig& config, EgoFn ego);

  // UTC ns of the frame next() gives next.
  std::int64_t next_stamp_ns() const noexcept;
  // The next frame in time order (stamp, id, dlc, data); false when no value could be encoded
  // (counted; `out` then holds no frame, call again for the next one).
  bool next(can::Frame& out);
  const VehicleCanCounters& counters() const noexcept { return counters_; }

 private:
  struct Stream {
    can::Frame frame;  // id, extended, dlc
    double period_s = 0, phase_s = 0;
    std::uint64_t index = 0;
    bool speed = false, yaw_rate = false;
    double time_s() const noexcept { return phase_s + static_cast<double>(index) * period_s; }
  };
  VehicleCanSim() = default;

  VehicleCanConfig config_;
  EgoFn ego_;
  can::OdometryDecoder::Channel speed_, yaw_rate_;
  Stream streams_[2];
  int stream_count_ = 0;
  VehicleCanCounters counters_;
};

}  // namespace stac::sim
