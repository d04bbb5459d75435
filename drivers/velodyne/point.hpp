// One decoded return in the sensor frame (x forward, y left, z up).
#pragma once

#include <cstdint>

namespace stac::velodyne {

struct Point {
  float x, y, z;                // m, sensor frame
  float intensity;              // corrected intensity, clamped to the laser's [min, max]
  float distance_m;             // raw distance x resolution + dist_correction (before two-point)
  std::int32_t time_offset_ns;  // firing time relative to the scan's stamp_ns
  std::uint16_t azimuth;        // raw block rotation, 0.01 deg (0..35999)
  std::uint8_t laser;           // laser id 0..63
  std::uint8_t ring;            // 0 = lowest beam (lasers sorted by vertical correction)
  std::uint8_t return_type;     // ReturnType: 0 strongest/single, 1 last
};
static_assert(sizeof(Point) == 32);

}  // namespace stac::velodyne
