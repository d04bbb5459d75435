#include "drivers/velodyne/beam.hpp"

#include <cmath>
#include <numbers>

namespace stac::velodyne {
namespace {

constexpr double kTwoPointXAt = 2.4, kTwoPointYAt = 1.93, kTwoPointFar = 25.04;

}  // namespace

Vec3 beam_point(const LaserCalibration& l, std::uint16_t rotation, double d,
                bool gate_two_point) noexcept {
  const double az = rotation * (std::numbers::pi / 18000.0) - l.rot_correction_rad;
  const double cos_a = std::cos(az), sin_a = std::sin(az);
  const double cv = std::cos(l.vert_correction_rad), sv = std::sin(l.vert_correction_rad);
  const double vo = l.vert_offset_m, ho = l.horiz_offset_m;
  double cx = 0.0, cy = 0.0;
  if (l.two_pt_correction_available) {
    const double xy = d * cv - vo * sv;
    const double xx = std::abs(xy * sin_a - ho * cos_a);
    const double yy = std::abs(xy * cos_a + ho * sin_a);
    const double dc = l.dist_correction_m;
    cx = (dc - l.dist_correction_x_m) * (xx - kTwoPointXAt) / (kTwoPointFar - kTwoPointXAt) +
         l.dist_correction_x_m - dc;
    cy = (dc - l.dist_correction_y_m) * (yy - kTwoPointYAt) / (kTwoPointFar - kTwoPointYAt) +
         l.dist_correction_y_m - dc;
    if (gate_two_point) {
      if (xx > kTwoPointFar) cx = 0.0;
      if (yy > kTwoPointFar) cy = 0.0;
    }
  }
  const double vx = ((d + cx) * cv - vo * sv) * sin_a - ho * cos_a;  // Velodyne: x right
  const double vy = ((d + cy) * cv - vo * sv) * cos_a + ho * sin_a;  // y forward
  const double vz = (d + cy) * sv + vo * cv;
  return {vy, -vx, vz};
}

BeamLine beam_line(const LaserCalibration& l, std::uint16_t rotation, double around_m,
                   bool gate_two_point) noexcept {
  // A short secant: both ends stay on one affine piece unless a kink lies within 1 mm.
  const double h = 1e-3;
  const Vec3 a = beam_point(l, rotation, around_m, gate_two_point);
  const Vec3 b = beam_point(l, rotation, around_m + h, gate_two_point);
  BeamLine line{};
  for (int i = 0; i < 3; ++i) {
    line.direction[i] = (b[i] - a[i]) / h;
    line.origin[i] = a[i] - line.direction[i] * around_m;
  }
  return line;
}

}  // namespace stac::velodyne
