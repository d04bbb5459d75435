// The grid (docs/segmentation.md): the scan's points binned into the fine x,y grid, per
// occupied cell its lowest point, the cells in the order they were first hit.
#include <algorithm>
#include <cmath>

#include "perception/segmentation/segmenter_state.hpp"

namespace stac::segmentation {

// Bin the points: per fine cell its lowest point. First a streaming pass keeps each point's
// dense cell index (kNone when ignored) in point_slot and its z in point_z; then the cells,
// with the grid entry of the point 16 ahead prefetched (slot_of is megabytes: its loads are
// the binning's cost).
void Segmenter::State::bin_points(const PointView& points, std::size_t count,
                                  const SegmenterConfig& c, SegmentCounters& k) noexcept {
  ground_cells.clear();
  cell_id.clear();
  (void)point_slot.resize(count);
  (void)point_z.resize(count);
  locate_points(points, count, c, k);
  const std::size_t slots = bin_cells(count, k);
  (void)cell_id.resize(slots);
  k.occupied_cells = slots;
  occupied = slots;
}

// The streaming pass: each point's dense cell index or kNone, counted by cause when ignored.
void Segmenter::State::locate_points(const PointView& points, std::size_t count,
                                     const SegmenterConfig& c, SegmentCounters& k) noexcept {
  State& s = *this;
  const float range = static_cast<float>(c.range_m);
  const float min_range2 = static_cast<float>(c.min_range_m * c.min_range_m);
  const float inv_cell = static_cast<float>(1.0 / c.cell_m);
  constexpr float kMaxAbsZ = 1e4f;  // also rejects NaN and infinities
  const float lowest = -static_cast<float>(c.sensor_height_m + c.below_ground_m);
  const float below_slope = static_cast<float>(c.below_ground_slope);
  for (std::size_t i = 0; i < count; ++i) {
    float x, y, z;
    points.read(i, x, y, z);
    s.point_slot[i] = kNone;
    if (!(std::fabs(x) < range && std::fabs(y) < range && std::fabs(z) < kMaxAbsZ) ||
        x * x + y * y < min_range2) {
      if (std::isfinite(x) && std::isfinite(y) && std::isfinite(z)) {
        ++k.ignored_out_of_range;
      } else {
        ++k.ignored_invalid;
      }
      continue;
    }
    if (z < lowest && z < lowest - below_slope * std::sqrt(x * x + y * y)) {  // sqrt if needed
      ++k.ignored_below;
      continue;
    }
    const auto ix = std::min(static_cast<std::uint32_t>((x + range) * inv_cell), s.n - 1);
    const auto iy = std::min(static_cast<std::uint32_t>((y + range) * inv_cell), s.n - 1);
    s.point_slot[i] = static_cast<std::uint32_t>(s.dense(ix, iy));  // < 2^32: n <= 20000
    s.point_z[i] = z;  // the later passes read 4 bytes a point instead of the whole record
  }
}

// The cells: each point's dense index replaced by its cell's slot (a new slot for a cell hit
// first, kNone and counted when they are all taken), per slot the lowest point.
std::size_t Segmenter::State::bin_cells(std::size_t count, SegmentCounters& k) noexcept {
  State& s = *this;
  std::size_t slots = 0;
  const std::size_t max_slots = s.cell_id.capacity();
  constexpr std::size_t kAhead = 16;
  for (std::size_t i = 0; i < count; ++i) {
    if (i + kAhead < count && s.point_slot[i + kAhead] != kNone) {
      __builtin_prefetch(&s.slot_of[s.point_slot[i + kAhead]], 1);
    }
    const std::uint32_t d = s.point_slot[i];
    if (d == kNone) continue;
    const float z = s.point_z[i];
    std::uint32_t& cell = s.slot_of[d];
    if (cell != kNone) {
      s.z_min[cell] = std::min(s.z_min[cell], z);
    } else {
      if (slots == max_slots) {
        ++k.dropped_cell_overflow;
        s.point_slot[i] = kNone;
        continue;
      }
      cell = static_cast<std::uint32_t>(slots++);
      // A new cell: its ix, iy from its dense index (not from the point again: its record was
      // streamed long ago and is a cache miss), its coarse cell the one holding its centre.
      const std::uint32_t id = s.cell_of_dense(d);
      s.cell_id[cell] = id;
      State::set(s.seen, d);
      s.coarse_id[cell] = s.coarse_row[id >> 16] + s.coarse_column[id & 0xFFFFu];
      s.z_min[cell] = z;
    }
    s.point_slot[i] = cell;
  }
  return slots;
}

}  // namespace stac::segmentation
