// Grid segmentation of one scan (STAC chapter 1, as on Junior): points are binned into a 2D
// grid over x,y; a cell is an obstacle when its points rise above a local ground estimate or
// spread vertically; 8-connected obstacle cells (plus links across unseen cells along the
// sensor's rays) form segments by a flood fill with a fixed queue; segments too small or too
// large are dropped. Everything is allocated at construction; segment() allocates nothing,
// never throws and counts every drop and overflow per cause.
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

// Every length in metres, slopes in m/m. Defaults = config/stac.yaml (docs/segmentation.md).
struct SegmenterConfig {
  // Grid.
  double cell_m = 0.15;      // obstacle grid resolution; Junior used 0.15
  double range_m = 80.0;     // the grid covers |x|, |y| < range_m; points beyond are ignored
  double min_range_m = 1.0;  // points closer than this in x,y are the vehicle itself: ignored
  // Ground. Returns below -(sensor_height_m + below_ground_m + below_ground_slope x range)
  // come from under the road (reflections, multipath) and are ignored.
  double sensor_height_m = 1.73;  // sensor origin above the ground under the vehicle
  double below_ground_m = 0.5;
  double below_ground_slope = 0.1;
  // Local ground: per coarse cell the second lowest of its fine cells' lowest points; then the
  // lowest, over the coarse cells within ground_radius_m, of that + ground_max_slope x distance
  // (a curb, or a cell a car hides, gets the ground of the road around it).
  double ground_cell_m = 1.05;
  double ground_radius_m = 3.0;
  double ground_max_slope = 0.05;
  double ground_clearance_m = 0.15;  // points at most this above the local ground are ground
  // A cell is a strong obstacle when its top is obstacle_height_m above the ground or its points
  // spread obstacle_spread_m vertically; with lower points above the clearance only it is weak
  // and joins an obstacle at most weak_join_cells cells deep.
  double obstacle_height_m = 0.30;
  double obstacle_spread_m = 0.25;
  std::uint32_t weak_join_cells = 2;
  // Strong cells link along the sensor's ray across cells where nothing was seen, up to
  // bridge_m, when their tops differ by at most bridge_height_m (car roofs hit by distant rings).
  double bridge_m = 1.5;
  double bridge_height_m = 0.3;
  // The walk also crosses cells where only ground was seen when the nearer of the two strong
  // cells is a low overhang: its lowest obstacle point is overhang_m..overhang_max_m above the
  // ground (a car body from 0.3 m up, with the road seen under it between the wheels; higher
  // overhangs are torsos and canopies; overhang_m 0: off); their tops may then differ by up
  // to overhang_height_m (a car's boot or bonnet and its cabin).
  double overhang_m = 0.0;
  double overhang_max_m = 0.6;
  double overhang_height_m = 0.6;
  double max_height_m = 2.5;  // points higher above the local ground are ignored (canopies)
  // A cell whose lowest obstacle point is at least overhead_m above the ground (only the lower
  // edge of a tree crown, a sign's panel) is overhead: it never connects with a cell standing
  // on the ground (flood fill, ray bridges), so a car or a person under a crown is not joined
  // to it and through it to the trunk. 0: off.
  double overhead_m = 0.0;
  // Split a component at its tops: its cells whose top is split_height_m above the ground
  // (shoulders and heads, a car's cabin) form high groups, linking cells up to 2 cells apart. A
  // group with footprint sides of at most split_person_m and at least split_min_points points
  // is one person; with two or more seeds (each person, plus one for all other high groups
  // together) every cell of the component goes to its nearest seed, each part a segment
  // (people walking in a file, a person beside a car or a pole). split_height_m 0: off.
  double split_height_m = 1.2;
  double split_person_m = 1.2;
  std::uint32_t split_min_points = 10;
  // Segments.
  std::uint32_t min_segment_points = 8;      // fewer obstacle points: dropped (too small)
  std::uint32_t max_segment_points = 60000;  // more: dropped (too large)
  double max_segment_extent_m = 15.0;        // a longer footprint side (cell bounds): dropped
  // Box heading: 0 = the principal axis of the XY footprint (the thesis); N > 0 = the
  // rectangle fit of L-shape fitting (the heading whose box edges the points lie closest to,
  // the "closeness" criterion of Zhang et al. 2017), searched over up to N of the segment's
  // points (evenly strided). A car seen at a corner shows an L whose principal axis is diagonal.
  std::uint32_t box_fit_points = 64;
  double box_fit_min_length_m = 2.5;  // ...for segments whose principal-axis box is this long
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

  // Segments one scan into `out` (cleared first; from make_segments(): smaller capacities only
  // count more overflow). `points` must hold `count` readable records. No allocation, no
  // exception, no I/O.
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
