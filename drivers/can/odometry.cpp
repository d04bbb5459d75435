#include "drivers/can/odometry.hpp"

#include <cmath>
#include <numbers>

namespace stac::can {
namespace {

rt::Result<OdometryDecoder::Channel> channel(const Database& db, const std::string& message,
                                             const std::string& signal, const char* what) {
  // Errors name the DBC file: the message or signal may be the configuration's typo or the
  // file's, and a garbage file holds no message at all.
  const std::string dbc = db.source.empty() ? std::string("the DBC") : db.source;
  const Message* m = db.find(message);
  if (m == nullptr) {
    return rt::make_error(dbc + ": " + what + ": no message '" + message + "'" +
                          (db.messages.empty()
                               ? " (it holds no message at all, no BO_ line: is it a DBC file?)"
                               : ""));
  }
  const Signal* s = m->find(signal);
  if (s == nullptr) {
    return rt::make_error(dbc + ": " + what + ": message '" + message + "' has no signal '" +
                          signal + "'");
  }
  if (s->multiplexer || s->multiplex_value >= 0) {
    return rt::make_error(dbc + ": " + what + ": signal '" + message + "." + signal +
                          "' is multiplexed; only plain signals can be mapped");
  }
  OdometryDecoder::Channel c;
  c.signal = *s;
  c.id = m->id;
  c.extended = m->extended;
  return c;
}

}  // namespace

rt::Result<OdometryDecoder> OdometryDecoder::create(const Database& db,
                                                    const OdometrySignalMap& map) {
  auto speed = channel(db, map.speed_message, map.speed_signal, "speed");
  if (!speed) return rt::Unexpected<rt::Error>{speed.error()};
  auto yaw = channel(db, map.yaw_rate_message, map.yaw_rate_signal, "yaw rate");
  if (!yaw) return rt::Unexpected<rt::Error>{yaw.error()};
  const std::string& su = speed->signal.unit;
  if (su == "m/s") {
    speed->scale = 1.0;
  } else if (su == "km/h" || su == "kph") {
    speed->scale = 1.0 / 3.6;
  } else {
    return rt::make_error("speed: signal '" + map.speed_message + "." + map.speed_signal +
                          "' has unit '" + su + "'; expected km/h or m/s");
  }
  const std::string& yu = yaw->signal.unit;
  if (yu == "deg/s" || yu == "\xC2\xB0/s") {
    yaw->scale = 1.0;
  } else if (yu == "rad/s") {
    yaw->scale = 180.0 / std::numbers::pi;
  } else {
    return rt::make_error("yaw rate: signal '" + map.yaw_rate_message + "." + map.yaw_rate_signal +
                          "' has unit '" + yu + "'; expected deg/s or rad/s");
  }
  if (map.yaw_rate_sign != 1.0 && map.yaw_rate_sign != -1.0) {
    return rt::make_error("yaw rate: the sign must be 1 or -1");
  }
  yaw->scale *= map.yaw_rate_sign;
  OdometryDecoder d;
  d.speed_ = *speed;
  d.yaw_rate_ = *yaw;
  return d;
}

OdometryUpdate OdometryDecoder::decode(const Frame& frame) noexcept {
  ++counters_.frames;
  OdometryUpdate u;
  u.stamp_ns = frame.stamp_ns;
  const auto matches = [&frame](const Channel& c) {
    return c.id == frame.id && c.extended == frame.extended;
  };
  const bool is_speed = matches(speed_);
  const bool is_yaw = matches(yaw_rate_);
  if (!is_speed && !is_yaw) {
    ++counters_.not_mapped;
    return u;
  }
  if (frame.remote || frame.error) {
    ++counters_.remote_or_error;
    return u;
  }
  const std::span<const std::uint8_t, 8> payload(frame.data);
  bool short_frame = false;
  if (is_speed) {
    if (frame.dlc >= speed_.signal.bytes_needed()) {
      u.has_speed = true;
      u.speed_mps = speed_.signal.decode(payload) * speed_.scale;
    } else {
      short_frame = true;
    }
  }
  if (is_yaw) {
    if (frame.dlc >= yaw_rate_.signal.bytes_needed()) {
      u.has_yaw_rate = true;
      u.yaw_rate_dps = yaw_rate_.signal.decode(payload) * yaw_rate_.scale;
    } else {
      short_frame = true;
    }
  }
  if (short_frame) ++counters_.short_frames;
  const bool bad_speed = u.has_speed && !(std::fabs(u.speed_mps) <= 200.0);
  const bool bad_yaw = u.has_yaw_rate && !(std::fabs(u.yaw_rate_dps) <= 720.0);
  if (bad_speed || bad_yaw) {
    ++counters_.implausible;
    if (bad_speed) u.has_speed = false, u.speed_mps = 0;
    if (bad_yaw) u.has_yaw_rate = false, u.yaw_rate_dps = 0;
  }
  if (u.has_speed || u.has_yaw_rate) ++counters_.decoded;
  return u;
}

std::vector<CanIdFilter> OdometryDecoder::filters() const {
  std::vector<CanIdFilter> f{{speed_.id, speed_.extended}};
  if (yaw_rate_.id != speed_.id || yaw_rate_.extended != speed_.extended)
    f.push_back({yaw_rate_.id, yaw_rate_.extended});
  return f;
}

const char* to_string(DeadReckoningStatus status) noexcept {
  switch (status) {
    case DeadReckoningStatus::kNoInput:
      return "no_input";
    case DeadReckoningStatus::kOk:
      return "ok";
    case DeadReckoningStatus::kStale:
      return "stale";
  }
  return "?";
}

void DeadReckoning::reset(const Pose2& pose) noexcept {
  pose_ = pose;
  started_ = true;
  have_speed_ = have_yaw_rate_ = false;
}

void DeadReckoning::integrate(std::int64_t t_ns, double speed_mps, double yaw_rate_dps) noexcept {
  const double dt = static_cast<double>(t_ns - pose_.stamp_ns) * 1e-9;
  const double w = yaw_rate_dps * std::numbers::pi / 180.0;
  const double yaw0 = pose_.yaw_rad;
  const double dyaw = w * dt;
  if (std::abs(dyaw) < 1e-9) {  // straight: the midpoint heading is exact to rounding
    const double mid = yaw0 + 0.5 * dyaw;
    pose_.x_m += speed_mps * dt * std::cos(mid);
    pose_.y_m += speed_mps * dt * std::sin(mid);
  } else {  // exact arc of radius v/w
    const double r = speed_mps / w;
    pose_.x_m += r * (std::sin(yaw0 + dyaw) - std::sin(yaw0));
    pose_.y_m -= r * (std::cos(yaw0 + dyaw) - std::cos(yaw0));
  }
  pose_.yaw_rad = std::remainder(yaw0 + dyaw, 2.0 * std::numbers::pi);
}

void DeadReckoning::update(const OdometryUpdate& u) noexcept {
  if (!u.has_speed && !u.has_yaw_rate) return;
  if (!started_) {
    pose_.stamp_ns = u.stamp_ns;
    started_ = true;
  }
  if (u.stamp_ns < pose_.stamp_ns) {
    ++out_of_order_;
    return;
  }
  if (have_speed_ && have_yaw_rate_ && u.stamp_ns > pose_.stamp_ns) {
    const std::int64_t t = u.stamp_ns;
    const bool fresh = t - speed_stamp_ns_ <= config_.stale_timeout_ns &&
                       t - yaw_rate_stamp_ns_ <= config_.stale_timeout_ns;
    if (fresh) {
      const double v = u.has_speed ? 0.5 * (speed_mps_ + u.speed_mps) : speed_mps_;
      const double w = u.has_yaw_rate ? 0.5 * (yaw_rate_dps_ + u.yaw_rate_dps) : yaw_rate_dps_;
      integrate(t, v, w);
    } else {
      ++gaps_;
    }
  }
  pose_.stamp_ns = u.stamp_ns;
  if (u.has_speed) {
    have_speed_ = true;
    speed_mps_ = u.speed_mps;
    speed_stamp_ns_ = u.stamp_ns;
  }
  if (u.has_yaw_rate) {
    have_yaw_rate_ = true;
    yaw_rate_dps_ = u.yaw_rate_dps;
    yaw_rate_stamp_ns_ = u.stamp_ns;
  }
}

DeadReckoningStatus DeadReckoning::status(std::int64_t now_ns) const noexcept {
  if (!have_speed_ || !have_yaw_rate_) return DeadReckoningStatus::kNoInput;
  if (now_ns - speed_stamp_ns_ > config_.stale_timeout_ns ||
      now_ns - yaw_rate_stamp_ns_ > config_.stale_timeout_ns) {
    return DeadReckoningStatus::kStale;
  }
  return DeadReckoningStatus::kOk;
}

}  // namespace stac::can
