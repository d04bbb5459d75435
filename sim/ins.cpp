#include "sim/ins.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace stac::sim {
namespace {

constexpr double kRadToDeg = 180.0 / std::numbers::pi;
constexpr std::int64_t kNsPerS = 1'000'000'000;
constexpr std::int64_t kNsPerWeek = applanix::kSecondsPerWeek * kNsPerS;
constexpr double kRateStepS = 0.05;    // central differences for rates and accelerations
constexpr double kClimbStepS = 0.005;  // central difference of the terrain height

// ENU <- NED and FRD <- FLU are their own inverses.
Eigen::Matrix3d enu_from_ned() {
  return (Eigen::Matrix3d() << 0, 1, 0, 1, 0, 0, 0, 0, -1).finished();
}
Eigen::Matrix3d frd_from_flu() {
  return Eigen::Vector3d(1, -1, -1).asDiagonal();
}

Eigen::Matrix3d attitude(const EgoState& e) {  // vehicle (FLU) -> sim world (ENU at the origin)
  return (Eigen::AngleAxisd(e.yaw, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(e.pitch, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(e.roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

double wrap_360(double deg) {
  double d = std::fmod(deg, 360.0);
  if (d < 0) d += 360.0;
  return d >= 360.0 ? 0.0 : d;
}

applanix::Group2 performance() {  // an RTK-fixed POS LV in open sky
  applanix::Group2 g;
  g.position_rms_m = {0.021f, 0.019f, 0.034f};
  g.velocity_rms_mps = {0.008f, 0.008f, 0.011f};
  g.attitude_rms_deg = {0.005f, 0.005f, 0.018f};
  g.ellipse_major_m = 0.024f;
  g.ellipse_minor_m = 0.017f;
  g.ellipse_orientation_deg = 35.0f;
  return g;
}

applanix::Group3 gnss_status(std::uint32_t week) {
  applanix::Group3 g;
  g.solution_status = 7;  // integer narrow-lane RTK
  // Twelve satellites spread over the sky (azimuth, elevation in deg), tracked on L1 and L2.
  static constexpr std::array<std::uint16_t, 12> kPrn{2, 5, 7, 9, 13, 15, 18, 20, 23, 26, 29, 31};
  for (std::size_t i = 0; i < kPrn.size(); ++i) {
    const double k = static_cast<double>(i);
    applanix::GnssChannel& c = g.channels[i];
    c.prn = kPrn[i];
    c.tracking_status = 5;
    c.azimuth_deg = static_cast<float>(std::fmod(17.0 + 30.0 * k, 360.0));
    c.elevation_deg = static_cast<float>(10.0 + std::fmod(23.0 * k, 70.0));
    c.l1_snr_dbhz = static_cast<float>(38.0 + 0.15 * c.elevation_deg);
    c.l2_snr_dbhz = c.l1_snr_dbhz - 6.0f;
  }
  g.channel_count = kPrn.size();
  g.sv_count = static_cast<std::uint8_t>(kPrn.size());
  g.hdop = 0.8f;
  g.vdop = 1.3f;
  g.dgps_latency_s = 1.0f;
  g.dgps_reference_id = 1;
  g.gps_week = week;
  g.gps_utc_offset_s = kGpsUtcLeapSeconds;
  g.message_latency_s = 0.02f;
  g.geoid_separation_m = -34.5f;
  g.receiver_type = 16;
  g.status = 0;
  return g;
}

}  // namespace

std::int64_t gps_ns_of_utc(std::int64_t utc_ns, int leap_s) noexcept {
  return utc_ns - kGpsEpochUnixS * kNsPerS + static_cast<std::int64_t>(leap_s) * kNsPerS;
}

GpsTime gps_time_of_gps_ns(std::int64_t gps_ns) noexcept {
  const std::int64_t week = gps_ns / kNsPerWeek;
  // One division of two exact doubles: the nearest double to the seconds of the week.
  return {static_cast<std::uint32_t>(week), static_cast<double>(gps_ns - week * kNsPerWeek) / 1e9};
}

InsSim::InsSim(const InsConfig& config, EgoFn ego)
    : config_(config),
      ego_(std::move(ego)),
      frame_(config.origin.lat_deg, config.origin.lon_deg, config.origin.alt_m) {
  start_gps_ns_ = gps_ns_of_utc(config_.start_ns);
  start_gps_ = gps_time_of_gps_ns(start_gps_ns_);
  const std::int64_t p = config_.group1_period_ns;
  sample_gps_ns_ = (start_gps_ns_ + p - 1) / p * p;  // the first multiple of the period
}

double InsSim::sim_time(std::int64_t gps_ns) const noexcept {
  return static_cast<double>(gps_ns - start_gps_ns_) * 1e-9;
}

std::int64_t InsSim::next_stamp_ns() const noexcept {
  return config_.start_ns + (sample_gps_ns_ - start_gps_ns_);
}

applanix::Group1 InsSim::group1_at(double t) const {
  const EgoState e = ego_(t);
  // World velocity (ENU at the origin): no side slip, plus the climb rate of the terrain.
  // Differences do not reach before sim time 0, where the trajectory is not defined.
  auto velocity = [this](double at, const EgoState& s) {
    const double lo = std::max(at - kClimbStepS, 0.0), hi = at + kClimbStepS;
    const double climb = (ego_(hi).z - ego_(lo).z) / (hi - lo);
    return Eigen::Vector3d(s.speed * std::cos(s.yaw), s.speed * std::sin(s.yaw), climb);
  };
  const double t_before = std::max(t - kRateStepS, 0.0), t_after = t + kRateStepS;
  const EgoState before = ego_(t_before), after = ego_(t_after);

  applanix::Group1 g;
  std::vector<double> m(9);  // GeographicLib's rotation: ENU at the fix -> ENU at the origin
  frame_.Reverse(e.x, e.y, e.z, g.latitude_deg, g.longitude_deg, g.altitude_m, m);
  const Eigen::Matrix3d origin_from_fix =
      Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(m.data());
  const Eigen::Matrix3d fix_from_origin = origin_from_fix.transpose();

  const Eigen::Matrix3d r = attitude(e);
  const Eigen::Matrix3d ned_from_frd = enu_from_ned() * fix_from_origin * r * frd_from_flu();
  g.heading_deg = wrap_360(std::atan2(ned_from_frd(1, 0), ned_from_frd(0, 0)) * kRadToDeg);
  g.pitch_deg = std::asin(std::clamp(-ned_from_frd(2, 0), -1.0, 1.0)) * kRadToDeg;
  g.roll_deg = std::atan2(ned_from_frd(2, 1), ned_from_frd(2, 2)) * kRadToDeg;
  g.wander_deg = 0.0;

  const Eigen::Vector3d v_ned = enu_from_ned() * fix_from_origin * velocity(t, e);
  g.north_velocity_mps = static_cast<float>(v_ned.x());
  g.east_velocity_mps = static_cast<float>(v_ned.y());
  g.down_velocity_mps = static_cast<float>(v_ned.z());
  const double speed = std::hypot(v_ned.x(), v_ned.y());
  g.speed_mps = static_cast<float>(speed);
  g.track_deg = static_cast<float>(
      speed > 1e-3 ? wrap_360(std::atan2(v_ned.y(), v_ned.x()) * kRadToDeg) : g.heading_deg);

  // Body rates: the rotation from t - h to t + h in the body frame.
  const Eigen::AngleAxisd turn(attitude(before).transpose() * attitude(after));
  const Eigen::Vector3d rate_frd =
      frd_from_flu() * turn.axis() * (turn.angle() / (t_after - t_before)) * kRadToDeg;
  g.rate_longitudinal_dps = static_cast<float>(rate_frd.x());
  g.rate_transverse_dps = static_cast<float>(rate_frd.y());
  g.rate_down_dps = static_cast<float>(rate_frd.z());
  const Eigen::Vector3d accel_world =
      (velocity(t_after, after) - velocity(t_before, before)) / (t_after - t_before);
  const Eigen::Vector3d accel_frd = frd_from_flu() * r.transpose() * accel_world;
  g.accel_longitudinal_mps2 = static_cast<float>(accel_frd.x());
  g.accel_transverse_mps2 = static_cast<float>(accel_frd.y());
  g.accel_down_mps2 = static_cast<float>(accel_frd.z());
  g.alignment_status = 0;  // full navigation
  return g;
}

InsMessage InsSim::next() {
  const double t = sim_time(sample_gps_ns_);
  applanix::TimeDistance td;
  td.time1_s = gps_time_of_gps_ns(sample_gps_ns_).seconds_of_week;
  td.time2_s = config_.pos_time_at_start_s + t;
  td.time_types = 0x01;  // time1 GPS, time2 POS
  td.distance_type = 1;  // POS distance
  InsMessage out;
  out.stamp_ns = next_stamp_ns();
  std::size_t n = 0;
  if (pending_ == 0) {
    const applanix::Group1 g = group1_at(t);
    if (!first_)
      distance_m_ +=
          0.5 * (last_speed_ + g.speed_mps) * static_cast<double>(config_.group1_period_ns) * 1e-9;
    first_ = false;
    last_speed_ = g.speed_mps;
    td.distance_tag_m = distance_m_;
    n = applanix::encode_group1(g, td, buffer_);
    out.group = 1;
    if (sample_gps_ns_ % kNsPerS == 0) {
      pending_ = 2;
    } else {
      sample_gps_ns_ += config_.group1_period_ns;
    }
  } else if (pending_ == 2) {
    td.distance_tag_m = distance_m_;
    n = applanix::encode_group2(performance(), td, buffer_);
    out.group = 2;
    pending_ = 3;
  } else {
    td.distance_tag_m = distance_m_;
    n = applanix::encode_group3(gnss_status(gps_time_of_gps_ns(sample_gps_ns_).week), td, buffer_);
    out.group = 3;
    pending_ = 0;
    sample_gps_ns_ += config_.group1_period_ns;
  }
  out.bytes = std::span<const std::uint8_t>(buffer_.data(), n);
  return out;
}

}  // namespace stac::sim
