#include "sim/vehicle_can.hpp"

#include <cmath>
#include <numbers>

namespace stac::sim {

rt::Result<VehicleCanSim> VehicleCanSim::create(const can::Database& db,
                                                const can::OdometrySignalMap& map,
                                                const VehicleCanConfig& config, EgoFn ego) {
  if (!(config.speed_rate_hz > 0) || !(config.yaw_rate_rate_hz > 0)) {
    return rt::make_error("CAN message rates must be positive");
  }
  auto decoder = can::OdometryDecoder::create(db, map);
  if (!decoder) return rt::Unexpected<rt::Error>{decoder.error()};
  VehicleCanSim sim;
  sim.config_ = config;
  sim.ego_ = std::move(ego);
  sim.speed_ = decoder->speed();
  sim.yaw_rate_ = decoder->yaw_rate();
  auto stream_for = [&](const can::OdometryDecoder::Channel& c, double rate_hz, double phase_s) {
    Stream s;
    s.frame.id = c.id;
    s.frame.extended = c.extended;
    const can::Message* m = db.find(c.id, c.extended);
    s.frame.dlc = m != nullptr ? m->dlc : can::kMaxDataBytes;
    s.period_s = 1.0 / rate_hz;
    s.phase_s = phase_s;
    return s;
  };
  const bool shared =
      sim.speed_.id == sim.yaw_rate_.id && sim.speed_.extended == sim.yaw_rate_.extended;
  if (shared) {
    Stream s = stream_for(sim.speed_, std::max(config.speed_rate_hz, config.yaw_rate_rate_hz),
                          config.yaw_rate_phase_s);
    s.speed = s.yaw_rate = true;
    sim.streams_[0] = s;
    sim.stream_count_ = 1;
  } else {
    sim.streams_[0] = stream_for(sim.speed_, config.speed_rate_hz, config.speed_phase_s);
    sim.streams_[0].speed = true;
    sim.streams_[1] = stream_for(sim.yaw_rate_, config.yaw_rate_rate_hz, config.yaw_rate_phase_s);
    sim.streams_[1].yaw_rate = true;
    sim.stream_count_ = 2;
  }
  return sim;
}

std::int64_t VehicleCanSim::next_stamp_ns() const noexcept {
  double t = streams_[0].time_s();
  for (int i = 1; i < stream_count_; ++i) t = std::min(t, streams_[i].time_s());
  return config_.start_ns + std::llround(t * 1e9);
}

bool VehicleCanSim::next(can::Frame& out) {
  Stream* s = &streams_[0];
  for (int i = 1; i < stream_count_; ++i) {
    if (streams_[i].time_s() < s->time_s()) s = &streams_[i];
  }
  const double t = s->time_s();
  ++s->index;
  const EgoState e = ego_(t);
  out = s->frame;
  out.stamp_ns = config_.start_ns + std::llround(t * 1e9);
  out.data = {};
  bool ok = true;
  // Physical value in the signal's unit: the decoder multiplies by `scale` to get m/s or deg/s.
  if (s->speed) ok = speed_.signal.encode(e.speed / speed_.scale, out.data) && ok;
  if (s->yaw_rate) {
    ok = yaw_rate_.signal.encode(e.yaw_rate * 180.0 / std::numbers::pi / yaw_rate_.scale,
                                 out.data) &&
         ok;
  }
  if (!ok) {
    ++counters_.unencodable;
    return false;
  }
  ++counters_.frames;
  return true;
}

}  // namespace stac::sim
