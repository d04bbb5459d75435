// A rotating HDL-64E made of packets: every return at a fixed distance, rotations advancing with
// the firing clock at a given (possibly drifting) RPM. For framing tests, not for realism.
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <vector>

#include "drivers/velodyne/calibration.hpp"
#include "drivers/velodyne/packet_builder.hpp"

namespace stac::testing {

// 64 lasers without offsets, elevations spread over -24..+3 deg: the azimuth of every point is
// its block's rotation exactly.
inline velodyne::Calibration flat_calibration() {
  velodyne::Calibration c;
  for (int i = 0; i < velodyne::kMaxLasers; ++i) {
    auto& l = c.lasers[static_cast<std::size_t>(i)];
    l.laser_id = i;
    l.vert_correction_rad = (-24.0 + 27.0 * i / 63.0) * 3.14159265358979 / 180.0;
  }
  return c;
}

struct StreamPacket {
  std::array<std::uint8_t, velodyne::kPacketSize> bytes;
  std::int64_t stamp_ns;
};

struct StreamSpec {
  double seconds = 1.0;
  std::function<double(double)> rpm = [](double) { return 600.0; };  // rpm at time t (s)
  double start_deg = 123.45;                                         // azimuth of the first firing
  std::uint16_t raw_distance = 5000;                                 // 10 m
  double packets_per_second = 3472.17;
  std::int64_t start_ns = 1'700'000'000'000'000'000;
};

// Single return, S2 timing: 6 firings (block pairs) per packet, 48 us apart.
inline std::vector<StreamPacket> make_stream(const StreamSpec& spec) {
  using namespace velodyne;
  std::vector<StreamPacket> out;
  const double period = 1.0 / spec.packets_per_second;
  const auto n = static_cast<std::size_t>(spec.seconds * spec.packets_per_second);
  double deg = spec.start_deg;
  double t = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    PacketBuilder b;
    for (int f = 0; f < 6; ++f) {
      const double tf = t + f * 48e-6;
      const auto rot =
          static_cast<std::uint16_t>(std::lround(std::fmod(deg, 360.0) * 100.0) % 36000);
      for (int half = 0; half < 2; ++half) {
        const int block = 2 * f + half;
        b.set_block(block, half == 0 ? kUpperBank : kLowerBank, rot);
        for (int j = 0; j < kLasersPerBlock; ++j) b.set_return(block, j, spec.raw_distance, 100);
      }
      deg += spec.rpm(tf) * 6.0 * 48e-6;  // rpm * 360 deg / 60 s
    }
    deg += spec.rpm(t) * 6.0 * (period - 6 * 48e-6);
    b.set_gps_trailer(static_cast<std::uint32_t>(k), 'H', 0);
    StreamPacket p{};
    std::copy(b.bytes().begin(), b.bytes().end(), p.bytes.begin());
    p.stamp_ns = spec.start_ns + static_cast<std::int64_t>(std::llround(t * 1e9));
    out.push_back(p);
    t += period;
  }
  return out;
}

}  // namespace stac::testing
