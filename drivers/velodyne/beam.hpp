// The decoder's point math for one return in double precision (REFERENCE §1, the ros-drivers/
// velodyne formulas): the reference the vectorised PacketDecoder is tested against, and the
// sensor model of the simulator. For one laser and block rotation the decoded point is affine
// in the corrected distance d, piece by piece (the two-point correction takes absolute values
// and, when gated, stops at 25.04 m), so a beam is cast as the line P(d) = origin + direction*d
// and re-linearised at the solution until it is exact.
#pragma once

#include <array>
#include <cstdint>

#include "drivers/velodyne/calibration.hpp"

namespace stac::velodyne {

using Vec3 = std::array<double, 3>;

// Decoded point (sensor frame: x forward, y left, z up) of a return of laser `l` in a block at
// `rotation` (0.01 deg), at corrected distance `distance_m` (raw * resolution + dist_correction).
Vec3 beam_point(const LaserCalibration& l, std::uint16_t rotation, double distance_m,
                bool gate_two_point) noexcept;

struct BeamLine {
  Vec3 origin;     // P(0) of the affine piece
  Vec3 direction;  // dP/dd (about unit length)
};

// The affine piece of P(d) around distance `around_m`.
BeamLine beam_line(const LaserCalibration& l, std::uint16_t rotation, double around_m,
                   bool gate_two_point) noexcept;

// The same math with every laser's trigonometry and a rotation table computed once, for the
// simulator's millions of beams per second.
class BeamModel {
 public:
  BeamModel(const Calibration& calibration, bool gate_two_point);
  Vec3 point(int laser, std::uint16_t rotation, double distance_m) const noexcept;
  BeamLine line(int laser, std::uint16_t rotation, double around_m) const noexcept;

  struct Laser {
    double cos_vert, sin_vert, cos_rot, sin_rot, vert_offset, horiz_offset;
    double dist, dist_x, dist_y;
    bool two_pt;
  };

 private:
  std::array<Laser, kMaxLasers> lasers_{};
  std::array<double, 36000> cos_{}, sin_{};
  bool gate_;
};

}  // namespace stac::velodyne
