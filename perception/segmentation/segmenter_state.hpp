// Internal to perception/segmentation: the segmenter's buffers and the steps of one scan over
// them, each step in the file of its part: grid.cpp (binning), ground.cpp (local ground, points
// against it), obstacle_cells.cpp, flood_fill.cpp (connected components, keeping segments),
// person_split.cpp, box_fit.cpp (centroids and oriented boxes). Allocated at construction
// (segmenter.cpp); the steps allocate nothing and never throw.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "perception/segmentation/segmenter.hpp"
#include "rt/fixed_vector.hpp"

namespace stac::segmentation {

namespace detail {

inline constexpr std::uint32_t kNoCell = std::numeric_limits<std::uint32_t>::max();

// A part of a component (the whole of it, or its cells nearest one seed when it is split).
struct Part {
  std::uint64_t points = 0;
  std::uint32_t cells = 0;
  std::uint32_t x0 = kNoCell, x1 = 0, y0 = kNoCell, y1 = 0;  // cell bounds
  double seed_x = 0, seed_y = 0;                             // sums of its seed cells' ix, iy
  std::uint32_t seed_cells = 0;
  std::uint32_t first = kNoCell;  // next point offset when kept, else kNoCell

  void add(std::uint32_t ix, std::uint32_t iy, std::uint32_t count) noexcept {
    points += count;
    ++cells;
    x0 = std::min(x0, ix), x1 = std::max(x1, ix), y0 = std::min(y0, iy), y1 = std::max(y1, iy);
  }
};

}  // namespace detail

// The segmenter's buffers. The dense fine grid maps a cell to its slot (kNone when empty) and is
// reset cell by cell after each scan; it is stored in 8 x 8 tiles so that the neighbouring returns
// of a ring hit the same cache lines. The coarse ground grid is reset the same way. Per occupied
// cell the data sits in compact "slot" arrays in the order the cells were first hit.
struct Segmenter::State {
  static constexpr std::uint32_t kNone = detail::kNoCell;
  // An obstacle cell not yet in a component.
  static constexpr std::uint32_t kUnvisited = kNone - 1;
  // Points above the clearance, but low: joins a component it touches, never starts one.
  static constexpr std::uint32_t kWeak = kNone - 2;
  // Split: more person-sized groups are foliage.
  static constexpr std::uint32_t kMaxPersons = 8;
  // Split: a high cell in the group being grown.
  static constexpr std::uint32_t kQueued = kNone - 2;

  using Part = detail::Part;

  // Every buffer at its capacity for `c` (segmenter.cpp).
  explicit State(const SegmenterConfig& c);

  std::uint32_t n, m;   // fine and coarse cells across
  std::uint32_t tiles;  // 8 x 8 tiles across the fine grid

  [[nodiscard]] std::size_t dense(std::uint32_t ix, std::uint32_t iy) const noexcept {
    return ((std::size_t{iy >> 3} * tiles + (ix >> 3)) << 6) | ((iy & 7u) << 3) | (ix & 7u);
  }
  // The inverse of dense(): iy << 16 | ix (as in cell_id).
  [[nodiscard]] std::uint32_t cell_of_dense(std::uint32_t d) const noexcept {
    const std::uint32_t tile = d >> 6;
    return ((tile / tiles) << 3 | (d >> 3 & 7u)) << 16 | (tile % tiles) << 3 | (d & 7u);
  }
  std::vector<std::uint32_t> slot_of;  // fine grid, tiled
  [[nodiscard]] std::size_t dense_of(std::uint32_t slot) const noexcept {
    return dense(cell_id[slot] & 0xFFFFu, cell_id[slot] >> 16);
  }
  // Cell flags, one bit per fine cell (bit d & 63 of word d >> 6 for dense index d: one word per
  // tile), tested in the flood fill and the split before slot_of and the per-slot arrays. open:
  // an obstacle cell (strong or weak) not yet in a component, zeroed with slot_of after the
  // scan; high: during a split, a high cell of the component not yet in a group, all zero
  // between splits.
  // seen: an occupied cell (anything was seen there), set in the binning and zeroed with
  // slot_of; the ray bridges walk over empty cells on it (144 kB for the default grid, which
  // stays in cache) instead of on slot_of (4.5 MB).
  std::vector<std::uint64_t> open, high, seen;
  static bool test(const std::vector<std::uint64_t>& bits, std::size_t d) noexcept {
    return (bits[d >> 6] >> (d & 63u) & 1u) != 0;
  }
  static void set(std::vector<std::uint64_t>& bits, std::size_t d) noexcept {
    bits[d >> 6] |= std::uint64_t{1} << (d & 63u);
  }
  static void unset(std::vector<std::uint64_t>& bits, std::size_t d) noexcept {
    bits[d >> 6] &= ~(std::uint64_t{1} << (d & 63u));
  }
  // Coarse grid with a border of `pad` cells (the ground window never leaves it); index
  // (gy + pad) * mp + gx + pad. ground_min is +inf where empty, reset cell by cell after use.
  std::uint32_t pad, mp;
  std::vector<float> ground_min, ground_min2, ground;
  struct Neighbour {
    std::ptrdiff_t offset;  // in the padded coarse grid
    float rise;             // max_slope x distance (m)
  };
  std::vector<Neighbour> window;                // the coarse cells within ground_radius_m
  rt::FixedVector<std::uint32_t> ground_cells;  // coarse cells hit this scan
  // Per fine column ix: gx + pad of the coarse cell that holds its centre; per fine row iy:
  // (gy + pad) * mp. A fine cell's coarse cell is their sum.
  std::vector<std::uint32_t> coarse_column, coarse_row;
  rt::FixedVector<std::uint32_t> point_slot;  // per point: its slot, or kNone
  rt::FixedVector<float> point_z;  // per binned point: its z, for the passes after the first
  // Per slot (occupied fine cell).
  rt::FixedVector<std::uint32_t> cell_id;  // iy << 16 | ix
  rt::FixedVector<std::uint32_t> coarse_id;
  rt::FixedVector<float> z_min, ground_at, band_max, band_min;  // ground_at: its local ground
  rt::FixedVector<std::uint32_t> obstacle_count, label, offset;
  // Flood fill.
  rt::FixedVector<std::uint8_t> depth;
  rt::FixedVector<std::uint8_t> overhead;  // 1: an overhead cell (SegmenterConfig::overhead_m)
  rt::FixedVector<std::uint32_t> component_cells;
  // Split: per slot of the component its part (or kNone), the queue of the high groups and then
  // of the nearest-seed fill, and the parts (seeds beyond max_segments join the shared one).
  rt::FixedVector<std::uint32_t> part;
  rt::FixedVector<std::uint32_t> split_queue;
  rt::FixedVector<Part> parts;
  rt::FixedVector<float> fit_x, fit_y;  // box fit: the sampled points about the centroid
  std::size_t occupied = 0;             // occupied cells this scan (cell_id's size)

  // The steps of one scan, in the order Segmenter::segment calls them.
  // grid.cpp: per point its fine cell, per occupied cell its lowest point.
  void bin_points(const PointView& points, std::size_t count, const SegmenterConfig& c,
                  SegmentCounters& k) noexcept;
  void locate_points(const PointView& points, std::size_t count, const SegmenterConfig& c,
                     SegmentCounters& k) noexcept;
  // Returns the occupied cells.
  std::size_t bin_cells(std::size_t count, SegmentCounters& k) noexcept;
  // ground.cpp
  void local_ground() noexcept;
  void classify_points(std::size_t count, const SegmenterConfig& c, SegmentCounters& k) noexcept;
  // obstacle_cells.cpp
  void mark_obstacle_cells(const SegmenterConfig& c) noexcept;
  // flood_fill.cpp: connected components, each kept or dropped whole or split. Returns the
  // points of the kept segments.
  std::uint32_t flood_fill(const SegmenterConfig& c, Segments& out) noexcept;
  // The ray bridges' limits (SegmenterConfig::bridge_m, overhang_m), as floats once per scan.
  struct RayBridge {
    explicit RayBridge(const SegmenterConfig& c) noexcept;
    int steps;  // of one cell
    float height, cell, range, inv_cell, overhang, overhang_height, overhang_top;
  };
  // The component of a strong cell, in component_cells; its points and cell bounds.
  Part grow_component(std::uint32_t seed, std::uint32_t comp, const RayBridge& b,
                      const SegmenterConfig& c) noexcept;
  void bridge(std::uint32_t slot, std::uint32_t cx, std::uint32_t cy, std::uint32_t comp,
              const RayBridge& b) noexcept;
  void walk_ray(std::uint32_t slot, float px, float py, float ux, float uy, float sign,
                std::uint32_t comp, const RayBridge& b) noexcept;
  // Fills parts and part: the component split at its people, else whole.
  void divide(const Part& whole, std::uint32_t comp, const SegmenterConfig& c) noexcept;
  void keep_parts(const SegmenterConfig& c, Segments& out, std::uint32_t& cursor) noexcept;
  void keep(Part& p, const SegmenterConfig& c, Segments& out, std::uint32_t& cursor) noexcept;
  void count_cells(SegmentCounters& k) const noexcept;
  void clear_grid() noexcept;
  void scatter(std::size_t count, std::uint32_t cursor, Segments& out) noexcept;
  // person_split.cpp
  bool split(std::uint32_t comp, const SegmenterConfig& c) noexcept;
  std::uint32_t mark_high_cells(const SegmenterConfig& c) noexcept;
  // False (no high bit left set) when the component is foliage; `shared` the seed of all
  // groups that are not one person (kNone: none).
  bool seed_parts(const SegmenterConfig& c, std::uint32_t& shared) noexcept;
  Part grow_high_group(std::uint32_t start) noexcept;
  void fill_from_seeds(std::uint32_t comp) noexcept;
  // Returns where the cells the fill did not reach begin in split_queue.
  std::size_t add_reached_cells() noexcept;
  void assign_unreached(std::size_t reached, std::uint32_t shared) noexcept;
  // box_fit.cpp
  void describe(const PointView& points, const SegmenterConfig& c, Segments& out) noexcept;
};

}  // namespace stac::segmentation
