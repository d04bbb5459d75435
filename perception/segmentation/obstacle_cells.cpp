// Obstacle cells (docs/segmentation.md): strong (high or spread vertically), weak (low points
// only, joined to an obstacle they touch) or overhead; open for the flood fill.
#include <algorithm>

#include "perception/segmentation/segmenter_state.hpp"

namespace stac::segmentation {

// Obstacle cells: high above the ground, or spread vertically (Junior's criterion). Cells
// with only low points above the clearance are weak: they join an obstacle they touch (a
// bumper, feet, the lower returns of a far car) up to weak_join_cells deep, never start one.
void Segmenter::State::mark_obstacle_cells(const SegmenterConfig& c) noexcept {
  State& s = *this;
  const std::size_t slots = s.occupied;
  const float obstacle_height = static_cast<float>(c.obstacle_height_m);
  const float obstacle_spread = static_cast<float>(c.obstacle_spread_m);
  const bool overhead_on = c.overhead_m > 0;
  const float overhead_low = static_cast<float>(c.overhead_m);
  for (std::size_t slot = 0; slot < slots; ++slot) {
    s.label[slot] = kNone;
    s.offset[slot] = kNone;
    if (s.obstacle_count[slot] == 0) continue;
    const float top = s.band_max[slot];
    const bool strong =
        top - s.ground_at[slot] > obstacle_height || top - s.z_min[slot] > obstacle_spread;
    s.label[slot] = strong ? kUnvisited : kWeak;
    s.overhead[slot] = overhead_on && s.band_min[slot] - s.ground_at[slot] >= overhead_low;
    State::set(s.open, s.dense_of(static_cast<std::uint32_t>(slot)));
  }
}

}  // namespace stac::segmentation
