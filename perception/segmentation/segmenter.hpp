// Grid segmentation of one scan (STAC chapter 1, as on Junior): points are binned into a 2D
// grid over x,y; a cell is an obstacle when its points rise above the local ground estimate or
// spread vertically; 8-connected obstacle cells form segments (flood fill with a fixed queue);
// segments too small or too large are dropped. Everything is allocated at construction;
// segment() allocates nothing, never throws and counts every overflow per cause.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>

#include "perception/segmentation/segments.hpp"
#include "rt/fixed_vector.hpp"

namespace stac::segmentation {

// Points read in place, no copy: point i's x,y,z are three consecutive floats at
// xyz + i * stride_bytes (bytes). KITTI float4 arrays: stride 16; the driver's 32-byte Point:
// stride 32. Sensor frame: x forward, y left, z up (m), sensor at the origin.
struct PointView {
  const float* xyz = nullptr;
  std::size_t count = 0;
  std::size_t stride_bytes = 3 * sizeof(float);

  void read(std::size_t i, float& x, float& y, float& z) const noexcept {
    float p[3];
    std::memcpy(p, reinterpret_cast<const unsigned char*>(xyz) + i * stride_bytes, sizeof(p));
    x = p[0];
    y = p[1];
    z = p[2];
  }
};

struct SegmenterConfig {
  // Grid.
  double cell_m = 0.15;          // obstacle grid resolution (m); Junior used 0.15
  double range_m = 80.0;         // the grid covers |x|, |y| < range_m (m); points beyond are ignored
  double min_range_m = 1.0;      // points closer than this in x,y are ignored (m): the vehicle itself
  // Ground.
  double sensor_height_m = 1.73;   // sensor origin above the ground under the vehicle (m)
  double below_ground_m = 0.5;     // returns lower than -(sensor_height_m + below_ground_m +
  double below_ground_slope = 0.1; // below_ground_slope x range) are from under the road
                                   // (reflections, multipath): ignored (m, m/m)
  double ground_cell_m = 1.05;   // coarse ground grid resolution (m): per cell its second lowest
                                 // point (one stray return below the road does not count)
  double ground_radius_m = 3.0;  // local ground = lowest over the coarse cells within this radius
  double ground_max_slope = 0.05;  // ...of their ground + max_slope x distance (m/m): the ground
                                   // of a curb or of a cell a car hides comes from the road around
  double ground_clearance_m = 0.15;  // points at most this above the local ground are ground (m)
  double obstacle_height_m = 0.30;   // a cell whose highest point is this far above ground is an obstacle (m)
  double obstacle_spread_m = 0.25;   // ...or whose points spread this much vertically (max - min z, m)
  std::uint32_t weak_join_cells = 2;  // cells with points only between the clearance and
                                      // obstacle_height_m join an obstacle this many cells deep
  double bridge_m = 1.5;          // strong cells link along the sensor's ray across cells where
  double bridge_height_m = 0.3;   // nothing was seen, up to this far, when their tops differ by
                                  // at most bridge_height_m (car roofs hit by rings far apart)
  double max_height_m = 2.5;     // points higher than this above the local ground are ignored (m)
  // Segments.
  std::uint32_t min_segment_points = 8;       // fewer obstacle points: dropped (too small)
  std::uint32_t max_segment_points = 30000;   // more: dropped (too large)
  double max_segment_extent_m = 15.0;  // a footprint side (axis-aligned cell bounds) longer: dropped (m)
  // Capacities (allocated at construction).
  std::size_t max_points = 300000;          // points per scan; beyond: counted, ignored
  std::size_t max_occupied_cells = 200000;  // occupied fine cells per scan; beyond: counted
  std::size_t max_segments = 2000;          // kept segments per scan; beyond: counted
};

// Empty when the configuration is usable, else what is wrong (for start-up checks).
const char* validate(const SegmenterConfig& config) noexcept;

class Segmenter {
 public:
  // Throws std::invalid_argument when validate() fails (start-up only).
  explicit Segmenter(const SegmenterConfig& config);
  Segmenter(const Segmenter&) = delete;
  Segmenter& operator=(const Segmenter&) = delete;
  Segmenter(Segmenter&&) noexcept;
  Segmenter& operator=(Segmenter&&) noexcept;
  ~Segmenter();

  // Segments one scan into `out` (cleared first; it must come from make_segments() of this
  // segmenter or have at least its capacities). No allocation, no exception.
  void segment(const PointView& points, Segments& out) noexcept;

  // Output storage sized for this configuration.
  [[nodiscard]] Segments make_segments() const;
  [[nodiscard]] const SegmenterConfig& config() const noexcept { return config_; }

 private:
  struct State;
  SegmenterConfig config_;
  std::unique_ptr<State> state_;
};

}  // namespace stac::segmentation
