// The local ground (docs/segmentation.md): per coarse cell the ground under it, from its own
// and its neighbours' lowest returns; each point against it: ground, too high, or obstacle.
#include <algorithm>
#include <limits>

#include "perception/segmentation/segmenter_state.hpp"

namespace stac::segmentation {

// Local ground: per coarse cell the second lowest of its fine cells' lowest points (a stray
// return below the road counts once; the lowest when alone); then the
// lowest over the cells within ground_radius_m of their value + max_slope x distance. A curb,
// or a cell where a car hides the road, thus gets the ground of the road around it.
void Segmenter::State::local_ground() noexcept {
  State& s = *this;
  const std::size_t slots = s.occupied;
  const float inf = std::numeric_limits<float>::infinity();
  for (std::size_t slot = 0; slot < slots; ++slot) {
    s.band_max[slot] = -inf;
    s.band_min[slot] = inf;
    s.obstacle_count[slot] = 0;
    const std::uint32_t g = s.coarse_id[slot];
    const float z = s.z_min[slot];
    if (s.ground_min[g] == inf) {
      s.ground_min[g] = z;
      s.ground_min2[g] = inf;
      (void)s.ground_cells.push_back(g);  // capacity m*m: never full
    } else if (z < s.ground_min[g]) {
      s.ground_min2[g] = s.ground_min[g];
      s.ground_min[g] = z;
    } else if (z < s.ground_min2[g]) {
      s.ground_min2[g] = z;
    }
  }
  for (const std::uint32_t g : s.ground_cells) {
    if (s.ground_min2[g] != inf) s.ground_min[g] = s.ground_min2[g];
  }
  for (const std::uint32_t g : s.ground_cells) {
    float low = s.ground_min[g];
    for (const State::Neighbour& w : s.window)
      low = std::min(low, s.ground_min[g + w.offset] + w.rise);
    s.ground[g] = low;
  }
  for (const std::uint32_t g : s.ground_cells) s.ground_min[g] = inf;  // empty again
  for (std::size_t slot = 0; slot < slots; ++slot) {
    s.ground_at[slot] = s.ground[s.coarse_id[slot]];  // one load per use below, not two
  }
}

// Points against their local ground: ground, above, or obstacle candidates per cell.
void Segmenter::State::classify_points(std::size_t count, const SegmenterConfig& c,
                                       SegmentCounters& k) noexcept {
  State& s = *this;
  const float clearance = static_cast<float>(c.ground_clearance_m);
  const float max_height = static_cast<float>(c.max_height_m);
  for (std::size_t i = 0; i < count; ++i) {
    const std::uint32_t slot = s.point_slot[i];
    if (slot == kNone) continue;
    const float z = s.point_z[i];
    const float h = z - s.ground_at[slot];
    if (h <= clearance) {
      ++k.ground_points;
      s.point_slot[i] = kNone;
    } else if (h > max_height) {
      ++k.ignored_above;
      s.point_slot[i] = kNone;
    } else {
      ++s.obstacle_count[slot];
      s.band_max[slot] = std::max(s.band_max[slot], z);
      s.band_min[slot] = std::min(s.band_min[slot], z);
    }
  }
}

}  // namespace stac::segmentation
