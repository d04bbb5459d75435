#include "ego/local_frame.hpp"

#include <numbers>

namespace stac::ego {
namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;

// ENU <- NED and FRD <- FLU are both their own inverses.
const Eigen::Matrix3d& enu_from_ned() {
  static const Eigen::Matrix3d m = (Eigen::Matrix3d() << 0, 1, 0, 1, 0, 0, 0, 0, -1).finished();
  return m;
}

}  // namespace

LocalFrame::LocalFrame(std::optional<Geodetic> origin) {
  if (origin) {
    frame_.Reset(origin->lat_deg, origin->lon_deg, origin->alt_m);
    anchored_ = true;
  }
}

Geodetic LocalFrame::origin() const noexcept {
  return {frame_.LatitudeOrigin(), frame_.LongitudeOrigin(), frame_.HeightOrigin()};
}

Eigen::Vector3d LocalFrame::to_local(const Geodetic& g) {
  if (!anchored_) {
    frame_.Reset(g.lat_deg, g.lon_deg, g.alt_m);
    anchored_ = true;
  }
  Eigen::Vector3d p;
  frame_.Forward(g.lat_deg, g.lon_deg, g.alt_m, p.x(), p.y(), p.z());
  return p;
}

Geodetic LocalFrame::to_geodetic(const Eigen::Vector3d& p) const {
  Geodetic g;
  frame_.Reverse(p.x(), p.y(), p.z(), g.lat_deg, g.lon_deg, g.alt_m);
  return g;
}

Eigen::Quaterniond LocalFrame::attitude_enu(double roll_deg, double pitch_deg,
                                            double heading_deg) noexcept {
  const Eigen::Matrix3d ned_from_frd =
      (Eigen::AngleAxisd(heading_deg * kDegToRad, Eigen::Vector3d::UnitZ()) *
       Eigen::AngleAxisd(pitch_deg * kDegToRad, Eigen::Vector3d::UnitY()) *
       Eigen::AngleAxisd(roll_deg * kDegToRad, Eigen::Vector3d::UnitX()))
          .toRotationMatrix();
  const Eigen::Matrix3d frd_from_flu = Eigen::Vector3d(1, -1, -1).asDiagonal();
  return Eigen::Quaterniond(enu_from_ned() * ned_from_frd * frd_from_flu).normalized();
}

PoseSample LocalFrame::pose(const InsFix& fix) {
  if (!anchored_) {
    frame_.Reset(fix.position.lat_deg, fix.position.lon_deg, fix.position.alt_m);
    anchored_ = true;
  }
  PoseSample p;
  p.stamp_ns = fix.stamp_ns;
  frame_.Forward(fix.position.lat_deg, fix.position.lon_deg, fix.position.alt_m, p.position_m.x(),
                 p.position_m.y(), p.position_m.z(), rotation_);
  // Rows of M rotate the ENU at the fix into the ENU at the origin.
  const Eigen::Matrix3d origin_from_fix =
      Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(rotation_.data());
  p.attitude = Eigen::Quaterniond(
                   origin_from_fix *
                   attitude_enu(fix.roll_deg, fix.pitch_deg, fix.heading_deg).toRotationMatrix())
                   .normalized();
  p.velocity_mps = origin_from_fix * enu_from_ned() * fix.velocity_ned_mps;
  p.angular_rate_rps = Eigen::Vector3d(fix.angular_rate_frd_dps.x(), -fix.angular_rate_frd_dps.y(),
                                       -fix.angular_rate_frd_dps.z()) *
                       kDegToRad;
  return p;
}

}  // namespace stac::ego
