#include "drivers/velodyne/beam.hpp"

#include <cmath>
#include <numbers>

namespace stac::velodyne {
namespace {

constexpr double kTwoPointXAt = 2.4, kTwoPointYAt = 1.93, kTwoPointFar = 25.04;

BeamModel::Laser laser_terms(const LaserCalibration& l) {
  return {std::cos(l.vert_correction_rad),
          std::sin(l.vert_correction_rad),
          std::cos(l.rot_correction_rad),
          std::sin(l.rot_correction_rad),
          l.vert_offset_m,
          l.horiz_offset_m,
          l.dist_correction_m,
          l.dist_correction_x_m,
          l.dist_correction_y_m,
          l.two_pt_correction_available};
}

// The ROS formula (REFERENCE §1) and its derivative in d, for cos/sin of the block rotation.
void evaluate(const BeamModel::Laser& l, double cos_r, double sin_r, double d, bool gate, Vec3& p,
              Vec3* dp) {
  const double cos_a = cos_r * l.cos_rot + sin_r * l.sin_rot;  // cos(rotation - rot_correction)
  const double sin_a = sin_r * l.cos_rot - cos_r * l.sin_rot;
  const double cv = l.cos_vert, sv = l.sin_vert, vo = l.vert_offset, ho = l.horiz_offset;
  double cx = 0.0, cy = 0.0, dcx = 0.0, dcy = 0.0;  // corrections and their slopes in d
  if (l.two_pt) {
    const double xy = d * cv - vo * sv;
    const double ex = xy * sin_a - ho * cos_a, ey = xy * cos_a + ho * sin_a;
    const double xx = std::abs(ex), yy = std::abs(ey);
    const double kx = (l.dist - l.dist_x) / (kTwoPointFar - kTwoPointXAt);
    const double ky = (l.dist - l.dist_y) / (kTwoPointFar - kTwoPointYAt);
    cx = kx * (xx - kTwoPointXAt) + l.dist_x - l.dist;
    cy = ky * (yy - kTwoPointYAt) + l.dist_y - l.dist;
    dcx = kx * (ex >= 0 ? 1.0 : -1.0) * cv * sin_a;
    dcy = ky * (ey >= 0 ? 1.0 : -1.0) * cv * cos_a;
    if (gate && xx > kTwoPointFar) cx = dcx = 0.0;
    if (gate && yy > kTwoPointFar) cy = dcy = 0.0;
  }
  const double vx = ((d + cx) * cv - vo * sv) * sin_a - ho * cos_a;  // Velodyne: x right
  const double vy = ((d + cy) * cv - vo * sv) * cos_a + ho * sin_a;  // y forward
  const double vz = (d + cy) * sv + vo * cv;
  p = {vy, -vx, vz};
  if (dp != nullptr) *dp = {(1 + dcy) * cv * cos_a, -(1 + dcx) * cv * sin_a, (1 + dcy) * sv};
}

}  // namespace

Vec3 beam_point(const LaserCalibration& l, std::uint16_t rotation, double d, bool gate) noexcept {
  const double r = rotation * (std::numbers::pi / 18000.0);
  Vec3 p{};
  evaluate(laser_terms(l), std::cos(r), std::sin(r), d, gate, p, nullptr);
  return p;
}

namespace {
BeamLine line_from(const Vec3& p, const Vec3& dp, double around) {
  BeamLine line{};
  for (int i = 0; i < 3; ++i) {
    line.direction[i] = dp[i];
    line.origin[i] = p[i] - dp[i] * around;
  }
  return line;
}
}  // namespace

BeamLine beam_line(const LaserCalibration& l, std::uint16_t rotation, double around_m,
                   bool gate) noexcept {
  const double r = rotation * (std::numbers::pi / 18000.0);
  Vec3 p{}, dp{};
  evaluate(laser_terms(l), std::cos(r), std::sin(r), around_m, gate, p, &dp);
  return line_from(p, dp, around_m);
}

BeamModel::BeamModel(const Calibration& calibration, bool gate_two_point) : gate_(gate_two_point) {
  for (int i = 0; i < kMaxLasers; ++i)
    lasers_[static_cast<std::size_t>(i)] =
        laser_terms(calibration.lasers[static_cast<std::size_t>(i)]);
  for (int r = 0; r < 36000; ++r) {
    cos_[static_cast<std::size_t>(r)] = std::cos(r * (std::numbers::pi / 18000.0));
    sin_[static_cast<std::size_t>(r)] = std::sin(r * (std::numbers::pi / 18000.0));
  }
}

Vec3 BeamModel::point(int laser, std::uint16_t rotation, double d) const noexcept {
  Vec3 p{};
  evaluate(lasers_[static_cast<std::size_t>(laser)], cos_[rotation], sin_[rotation], d, gate_, p,
           nullptr);
  return p;
}

BeamLine BeamModel::line(int laser, std::uint16_t rotation, double around_m) const noexcept {
  Vec3 p{}, dp{};
  evaluate(lasers_[static_cast<std::size_t>(laser)], cos_[rotation], sin_[rotation], around_m,
           gate_, p, &dp);
  return line_from(p, dp, around_m);
}

}  // namespace stac::velodyne
