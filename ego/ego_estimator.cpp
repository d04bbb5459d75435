#include "ego/ego_estimator.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <variant>

namespace stac::ego {
namespace {

constexpr std::int64_t kGpsEpochUnixNs = 315'964'800'000'000'000;  // 1980-01-06T00:00:00Z

double yaw_of(const Eigen::Quaterniond& q) noexcept {
  const Eigen::Vector3d x = q * Eigen::Vector3d::UnitX();
  return std::atan2(x.y(), x.x());
}

}  // namespace

std::int64_t gps_to_utc_ns(std::int64_t gps_ns, double gps_utc_offset_s) noexcept {
  return gps_ns + kGpsEpochUnixNs - std::llround(gps_utc_offset_s * 1e9);
}

const char* to_string(EgoSource s) noexcept {
  switch (s) {
    case EgoSource::kIns:
      return "ins";
    case EgoSource::kDeadReckoning:
      return "dead reckoning";
    case EgoSource::kLost:
      return "lost";
    case EgoSource::kNone:
      break;
  }
  return "none";
}

EgoEstimator::EgoEstimator(const EgoEstimatorConfig& config, LocalFrame& frame,
                           PoseHistory& history) noexcept
    : config_(config), frame_(frame), history_(history), odometry_(config.odometry) {}

namespace {}  // namespace

void EgoEstimator::add_ins(const applanix::Parsed& message,
                           const applanix::StreamParser& parser) noexcept {
  const auto* g = std::get_if<applanix::Group1>(&message.content);
  if (g == nullptr) return;
  if (!message.time1_gps_ns) {
    ++counters_.no_absolute_time;
    return;
  }
  if (g->alignment_status > config_.max_alignment_status) {
    ++counters_.not_aligned;
    return;
  }
  if (!applanix::plausible(*g)) {
    ++counters_.impossible;
    return;
  }
  add_fix(ins_fix(*g, gps_to_utc_ns(*message.time1_gps_ns, parser.gps_utc_offset_s())));
}

InsFix ins_fix(const applanix::Group1& g, std::int64_t stamp_ns) noexcept {
  InsFix fix;
  fix.stamp_ns = stamp_ns;
  fix.position = {g.latitude_deg, g.longitude_deg, g.altitude_m};
  fix.roll_deg = g.roll_deg;
  fix.pitch_deg = g.pitch_deg;
  fix.heading_deg = g.heading_deg;
  fix.velocity_ned_mps = {g.north_velocity_mps, g.east_velocity_mps, g.down_velocity_mps};
  fix.angular_rate_frd_dps = {g.rate_longitudinal_dps, g.rate_transverse_dps, g.rate_down_dps};
  return fix;
}

void EgoEstimator::add_fix(const InsFix& fix) noexcept {
  const PoseSample pose = frame_.pose(fix);
  // A fix over kTimeJumpNs after the last one, or before it, counts only when the next follows
  // it within kConfirmNs (the INS back after an outage, a replay looping, the clock corrected
  // after bad fixes); alone, it was a corrupted time. A jump back starts a new timeline in the
  // history (the poses before it are not this time's).
  constexpr std::int64_t kTimeJumpNs = 1'000'000'000, kConfirmNs = 100'000'000;
  const std::int64_t step = have_ins_ ? pose.stamp_ns - last_ins_.stamp_ns : 0;
  if (have_ins_ && (step > kTimeJumpNs || step < -kTimeJumpNs)) {
    const bool confirms = have_after_jump_ && pose.stamp_ns > after_jump_.stamp_ns &&
                          pose.stamp_ns - after_jump_.stamp_ns <= kConfirmNs;
    if (!confirms) {
      if (have_after_jump_) ++counters_.time_jumps;
      after_jump_ = pose;
      have_after_jump_ = true;
      return;
    }
    have_after_jump_ = false;
    if (after_jump_.stamp_ns < last_ins_.stamp_ns) {
      ++counters_.backward_jumps;
      if (!history_.restart(after_jump_)) {
        ++counters_.rejected;
        return;
      }
      commit(after_jump_);
    } else {
      accept(after_jump_);
    }
  } else if (have_after_jump_) {
    ++counters_.time_jumps;  // the fixes went on from before it
    have_after_jump_ = false;
  }
  accept(pose);
}

void EgoEstimator::accept(const PoseSample& pose) noexcept {
  if (!history_.push(pose)) {
    ++counters_.rejected;
    return;
  }
  commit(pose);
}

void EgoEstimator::commit(const PoseSample& pose) noexcept {
  ++counters_.ins_fixes;
  last_ins_ = pose;
  have_ins_ = true;
  last_pushed_ns_ = pose.stamp_ns;
  // Dead reckoning restarts from every fix, so it continues from the last one if the INS goes.
  odometry_.reset(
      can::Pose2{pose.stamp_ns, pose.position_m.x(), pose.position_m.y(), yaw_of(pose.attitude)});
}

void EgoEstimator::add_odometry(const can::OdometryUpdate& update) noexcept {
  odometry_.update(update);
  if (!have_ins_ || update.stamp_ns - last_ins_.stamp_ns <= config_.ins_timeout_ns) return;
  if (odometry_.status(update.stamp_ns) != can::DeadReckoningStatus::kOk) return;
  const can::Pose2& p = odometry_.pose();
  if (p.stamp_ns - last_pushed_ns_ < config_.dead_reckoning_period_ns) return;
  // Height, roll and pitch held from the last fix; heading and position from odometry.
  const Eigen::Matrix3d r = last_ins_.attitude.toRotationMatrix();  // Rz(yaw) Ry(pitch) Rx(roll)
  const double pitch = std::asin(std::clamp(-r(2, 0), -1.0, 1.0));
  const double roll = std::atan2(r(2, 1), r(2, 2));
  PoseSample s;
  s.stamp_ns = p.stamp_ns;
  s.position_m = {p.x_m, p.y_m, last_ins_.position_m.z()};
  s.attitude = from_roll_pitch_yaw(roll, pitch, p.yaw_rad);
  const double speed =
      update.has_speed ? update.speed_mps : last_ins_.velocity_mps.head<2>().norm();
  s.velocity_mps = {speed * std::cos(p.yaw_rad), speed * std::sin(p.yaw_rad), 0.0};
  if (update.has_yaw_rate)
    s.angular_rate_rps = {0.0, 0.0, update.yaw_rate_dps * std::numbers::pi / 180.0};
  if (!history_.push(s)) {
    ++counters_.rejected;
    return;
  }
  ++counters_.dead_reckoned;
  last_pushed_ns_ = s.stamp_ns;
}

EgoSource EgoEstimator::source(std::int64_t now_ns) const noexcept {
  if (!have_ins_) return EgoSource::kNone;
  if (now_ns - last_ins_.stamp_ns <= config_.ins_timeout_ns) return EgoSource::kIns;
  return odometry_.status(now_ns) == can::DeadReckoningStatus::kOk ? EgoSource::kDeadReckoning
                                                                   : EgoSource::kLost;
}

}  // namespace stac::ego
