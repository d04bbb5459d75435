// The local world frame: ENU (x east, y north, z up) on the tangent plane of a geodetic origin,
// either configured or the first fix (GeographicLib::LocalCartesian on WGS84). Turns an INS
// navigation solution (Applanix Group 1: lat/lon/alt, NED velocity, Tate-Bryant roll/pitch/
// heading of the x-forward/y-right/z-down body) into a PoseSample of the vehicle (x forward,
// y left, z up) in that frame. Attitude and velocity are rotated from the ENU at the fix into
// the ENU at the origin (meridian convergence), so the frame stays consistent kilometres away.
#pragma once

#include <GeographicLib/LocalCartesian.hpp>
#include <cstdint>
#include <optional>
#include <vector>

#include "ego/pose.hpp"

namespace stac::ego {

struct Geodetic {
  double lat_deg = 0, lon_deg = 0, alt_m = 0;  // WGS84, ellipsoidal height
};

struct InsFix {
  std::int64_t stamp_ns = 0;  // pose clock
  Geodetic position;
  double roll_deg = 0, pitch_deg = 0,
         heading_deg = 0;  // Tate-Bryant, NED, body x fwd y right z down
  Eigen::Vector3d velocity_ned_mps = Eigen::Vector3d::Zero();
  Eigen::Vector3d angular_rate_frd_dps = Eigen::Vector3d::Zero();  // longitudinal, transverse, down
};

class LocalFrame {
 public:
  // Without an origin, the first fix given to pose() becomes it.
  explicit LocalFrame(std::optional<Geodetic> origin = std::nullopt);

  [[nodiscard]] bool anchored() const noexcept { return anchored_; }
  [[nodiscard]] Geodetic origin() const noexcept;
  // ENU coordinates (m) of a geodetic position; anchors at it when not anchored yet.
  Eigen::Vector3d to_local(const Geodetic& g);
  // The geodetic position of local ENU coordinates (m); the frame must be anchored.
  [[nodiscard]] Geodetic to_geodetic(const Eigen::Vector3d& p) const;
  // The vehicle pose of an INS fix; anchors at it when not anchored yet. No allocation.
  PoseSample pose(const InsFix& fix);

  // Vehicle (x fwd, y left, z up) -> local ENU at the fix, from NED Tate-Bryant angles (deg).
  static Eigen::Quaterniond attitude_enu(double roll_deg, double pitch_deg,
                                         double heading_deg) noexcept;

 private:
  GeographicLib::LocalCartesian frame_;
  bool anchored_ = false;
  std::vector<double> rotation_ = std::vector<double>(9);  // GeographicLib's M, reused per fix
};

}  // namespace stac::ego
