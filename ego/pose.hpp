// A timed pose of the vehicle in the local world frame, and the rigid-transform helpers the
// ego-motion stages share. Frames: world = local ENU (x east, y north, z up) anchored at a
// geodetic origin; vehicle = x forward, y left, z up; sensor = the HDL-64E's (x forward, y left,
// z up) placed on the vehicle by the extrinsics.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>

namespace stac::ego {

struct PoseSample {
  std::int64_t stamp_ns = 0;                                     // pose clock (GPS or UTC), ns
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();          // vehicle origin, world frame
  Eigen::Quaterniond attitude = Eigen::Quaterniond::Identity();  // vehicle -> world
  Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();        // world frame
  Eigen::Vector3d angular_rate_rps = Eigen::Vector3d::Zero();    // vehicle frame
};

// world_T_vehicle of a sample.
inline Eigen::Isometry3d to_isometry(const PoseSample& p) noexcept {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = p.attitude.toRotationMatrix();
  t.translation() = p.position_m;
  return t;
}

// A rotation from roll, pitch, yaw (rad) applied as R = Rz(yaw) Ry(pitch) Rx(roll), the
// convention of the extrinsics in config/stac.yaml.
inline Eigen::Quaterniond from_roll_pitch_yaw(double roll, double pitch, double yaw) noexcept {
  return Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                            Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                            Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()));
}

}  // namespace stac::ego
