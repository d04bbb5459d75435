#include "tools/demo_capture.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "drivers/velodyne/decoder.hpp"
#include "drivers/velodyne/packet_builder.hpp"

namespace stac::tools {
namespace {

constexpr double kSensorHeightM = 1.73;  // KITTI's mounting height
constexpr double kRpm = 600.0;

struct Box {
  double x0, x1, y0, y1, z0, z1;  // sensor frame, m
  std::uint8_t intensity;
};

// The yard: objects first; the walls are the inside of the last box.
constexpr Box kObjects[] = {
    {8.0, 12.5, -5.0, -3.2, -1.73, -0.28, 60},    // a car
    {-14.0, -8.5, 4.0, 6.1, -1.73, 0.67, 90},     // a van
    {4.6, 5.1, 6.0, 6.5, -1.73, 0.02, 30},        // a pedestrian-sized block
    {20.0, 21.0, -12.0, 12.0, -1.73, -0.73, 120}, // a low wall
};
constexpr Box kYard{-30.0, 40.0, -18.0, 18.0, -1.73, 3.0, 80};
constexpr double kPoleX = 6.0, kPoleY = -8.0, kPoleR = 0.15;

// Distance along the unit ray (d) from the origin to a box, or +inf.
double hit_box(const Box& b, const double d[3]) {
  const double lo[3] = {b.x0, b.y0, b.z0}, hi[3] = {b.x1, b.y1, b.z1};
  double t0 = 0.0, t1 = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    if (std::abs(d[a]) < 1e-12) {
      if (lo[a] > 0.0 || hi[a] < 0.0) return std::numeric_limits<double>::infinity();
      continue;
    }
    double ta = lo[a] / d[a], tb = hi[a] / d[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  return t0 <= t1 && t0 > 0.0 ? t0 : std::numeric_limits<double>::infinity();
}

// Range and intensity of the first surface along the ray; range +inf when nothing is hit.
std::pair<double, std::uint8_t> cast(const double d[3]) {
  double best = std::numeric_limits<double>::infinity();
  std::uint8_t intensity = 0;
  for (const Box& b : kObjects) {
    const double t = hit_box(b, d);
    if (t < best) best = t, intensity = b.intensity;
  }
  if (d[2] < 0.0) {
    const double t = -kSensorHeightM / d[2];
    if (t < best) best = t, intensity = 25;
  }
  // Pole: vertical cylinder, solve |o + t d - c|^2 = r^2 in XY.
  const double a = d[0] * d[0] + d[1] * d[1];
  const double b = -2.0 * (d[0] * kPoleX + d[1] * kPoleY);
  const double c = kPoleX * kPoleX + kPoleY * kPoleY - kPoleR * kPoleR;
  const double disc = b * b - 4 * a * c;
  if (a > 0 && disc >= 0) {
    const double t = (-b - std::sqrt(disc)) / (2 * a);
    if (t > 0 && t < best && t * d[2] < 3.0) best = t, intensity = 200;
  }
  // Walls: leaving the yard box from inside.
  double exit = std::numeric_limits<double>::infinity();
  const double lo[3] = {kYard.x0, kYard.y0, -1e9}, hi[3] = {kYard.x1, kYard.y1, kYard.z1};
  for (int ax = 0; ax < 3; ++ax) {
    if (d[ax] > 1e-12) exit = std::min(exit, hi[ax] / d[ax]);
    if (d[ax] < -1e-12) exit = std::min(exit, lo[ax] / d[ax]);
  }
  if (exit < best && exit * d[2] < kYard.z1 - 1e-6) best = exit, intensity = kYard.intensity;
  return {best, intensity};
}

}  // namespace

std::vector<DemoPacket> make_demo_capture(const velodyne::Calibration& calibration, double seconds,
                                          std::int64_t start_ns) {
  using namespace velodyne;
  const ModelTraits& model = traits(Model::kS2_1);
  const double packets_per_s = model.packets_per_second_single;
  const auto count = static_cast<std::size_t>(seconds * packets_per_s);
  const double deg_per_us = kRpm * 360.0 / 60.0 * 1e-6;
  // Firing offsets from the decoder's own tables, so the capture and the driver agree.
  const PacketDecoder timing(calibration, DecoderConfig{.model = Model::kS2_1});
  std::vector<DemoPacket> out(count);
  for (std::size_t k = 0; k < count; ++k) {
    const double t0_us = static_cast<double>(k) * 1e6 / packets_per_s;
    PacketBuilder b;
    for (int block = 0; block < kBlocksPerPacket; ++block) {
      const int bank = block % 2;
      const double t_us = t0_us + timing.firing_offset_ns(block, 0, false) * 1e-3;
      const double az_deg = std::fmod(t_us * deg_per_us, 360.0);
      const auto rotation = static_cast<std::uint16_t>(std::lround(az_deg * 100.0) % 36000);
      b.set_block(block, bank == 0 ? kUpperBank : kLowerBank, rotation);
      for (int j = 0; j < kLasersPerBlock; ++j) {
        const LaserCalibration& l = calibration.lasers[static_cast<std::size_t>(bank * 32 + j)];
        const double az = rotation * std::numbers::pi / 18000.0 - l.rot_correction_rad;
        const double cv = std::cos(l.vert_correction_rad);
        const double d[3] = {std::cos(az) * cv, -std::sin(az) * cv, std::sin(l.vert_correction_rad)};
        const auto [range, intensity] = cast(d);
        const double raw = (range - l.dist_correction_m) / calibration.distance_resolution_m;
        if (!std::isfinite(raw) || raw < 1.0 || raw > 65535.0) continue;  // no return
        b.set_return(block, j, static_cast<std::uint16_t>(std::lround(raw)), intensity);
      }
    }
    const std::int64_t first_firing_ns = start_ns + std::llround(t0_us * 1e3);
    const auto usec_past_hour = static_cast<std::uint32_t>((first_firing_ns / 1000) % 3'600'000'000LL);
    b.set_gps_trailer(usec_past_hour, 0, 0);
    std::copy(b.bytes().begin(), b.bytes().end(), out[k].bytes.begin());
    out[k].receive_stamp_ns = first_firing_ns + timing.packet_span_ns(false);
  }
  return out;
}

}  // namespace stac::tools
