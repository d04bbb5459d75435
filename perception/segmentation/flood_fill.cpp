// Connected components (docs/segmentation.md): a flood fill of 8-connected obstacle cells with a
// fixed queue, linked across unseen cells along the sensor's rays; each component split at its
// people (person_split.cpp) or whole, its parts kept as segments or dropped, their points
// scattered contiguous per segment.
#include <algorithm>
#include <cmath>

#include "perception/segmentation/segmenter_state.hpp"

namespace stac::segmentation {

Segmenter::State::RayBridge::RayBridge(const SegmenterConfig& c) noexcept
    : steps(static_cast<int>(c.bridge_m / c.cell_m)),
      height(static_cast<float>(c.bridge_height_m)),
      cell(static_cast<float>(c.cell_m)),
      range(static_cast<float>(c.range_m)),
      inv_cell(static_cast<float>(1.0 / c.cell_m)),
      overhang(static_cast<float>(c.overhang_m)),
      overhang_height(static_cast<float>(c.overhang_height_m)),
      overhang_top(static_cast<float>(c.overhang_max_m)) {}

// Flood fill 8-connected obstacle cells (a fixed queue, no recursion); keep or drop each.
std::uint32_t Segmenter::State::flood_fill(const SegmenterConfig& c, Segments& out) noexcept {
  const RayBridge ray_bridge(c);
  std::uint32_t cursor = 0;
  std::uint32_t component = 0;
  for (std::size_t seed = 0; seed < occupied; ++seed) {
    if (label[seed] != kUnvisited) continue;  // components start at strong cells only
    const Part whole = grow_component(static_cast<std::uint32_t>(seed), component, ray_bridge, c);
    ++out.counters.clusters;
    divide(whole, component, c);
    ++component;
    keep_parts(c, out, cursor);
  }
  count_cells(out.counters);
  clear_grid();
  return cursor;
}

// Breadth first: component_cells is the queue. depth: 0 for strong cells, else the weak steps
// from the nearest strong cell; weak cells spread only up to weak_join_cells deep.
Segmenter::State::Part Segmenter::State::grow_component(std::uint32_t seed, std::uint32_t comp,
                                                        const RayBridge& b,
                                                        const SegmenterConfig& c) noexcept {
  State& s = *this;
  const std::uint32_t side = n;  // a local: the stores below cannot change it
  s.component_cells.clear();
  s.label[seed] = comp;
  State::unset(s.open, s.dense_of(seed));
  s.depth[seed] = 0;
  (void)s.component_cells.push_back(seed);  // each cell once
  std::uint64_t pts = 0;
  std::uint32_t x0 = side, x1 = 0, y0 = side, y1 = 0;
  for (std::size_t head = 0; head < s.component_cells.size(); ++head) {
    const std::uint32_t slot = s.component_cells[head];
    const std::uint32_t id = s.cell_id[slot];
    const std::uint32_t cx = id & 0xFFFFu, cy = id >> 16;
    x0 = std::min(x0, cx), x1 = std::max(x1, cx), y0 = std::min(y0, cy), y1 = std::max(y1, cy);
    pts += s.obstacle_count[slot];
    const bool spreads_weak = s.depth[slot] < c.weak_join_cells;
    for (std::uint32_t yy = cy == 0 ? 0 : cy - 1; yy <= std::min(cy + 1, side - 1); ++yy) {
      for (std::uint32_t xx = cx == 0 ? 0 : cx - 1; xx <= std::min(cx + 1, side - 1); ++xx) {
        const std::size_t d = s.dense(xx, yy);
        if (!State::test(s.open, d)) continue;  // empty, ground only, or in a component
        const std::uint32_t other = s.slot_of[d];
        if (s.overhead[other] != s.overhead[slot]) continue;  // standing vs overhead: apart
        if (s.label[other] == kUnvisited) {
          s.depth[other] = 0;
        } else if (spreads_weak) {  // weak
          s.depth[other] = static_cast<std::uint8_t>(s.depth[slot] + 1);
        } else {
          continue;
        }
        State::unset(s.open, d);
        s.label[other] = comp;
        (void)s.component_cells.push_back(other);
      }
    }
    if (s.depth[slot] == 0 && b.steps > 0) bridge(slot, cx, cy, comp, b);
  }
  return Part{pts, static_cast<std::uint32_t>(s.component_cells.size()), x0, x1, y0, y1};
}

// Across unseen cells along the sensor's ray: the roof of a car beside the sensor is hit by
// rings far apart (1 m and more at 8 m) with nothing seen between them (the roof between
// rings is not sampled, the road under it is hidden). A strong cell links to the first strong
// cell within bridge_m outward or inward along its ray when every cell crossed is empty and
// their tops differ by at most bridge_height_m; the first cell where anything was seen ends
// the walk (a cell of the component itself walks on from there when its turn comes).
void Segmenter::State::bridge(std::uint32_t slot, std::uint32_t cx, std::uint32_t cy,
                              std::uint32_t comp, const RayBridge& b) noexcept {
  const float px = (static_cast<float>(cx) + 0.5f) * b.cell - b.range;
  const float py = (static_cast<float>(cy) + 0.5f) * b.cell - b.range;
  const float r = std::sqrt(px * px + py * py);
  if (r < b.cell) return;
  const float ux = b.cell * px / r, uy = b.cell * py / r;
  for (const float sign : {1.0f, -1.0f}) walk_ray(slot, px, py, ux, uy, sign, comp, b);
}

// One direction of a ray bridge from the cell at (px, py), in steps (ux, uy) of one cell.
void Segmenter::State::walk_ray(std::uint32_t slot, float px, float py, float ux, float uy,
                                float sign, std::uint32_t comp, const RayBridge& b) noexcept {
  State& s = *this;
  const std::uint32_t side = n;  // a local: the stores below cannot change it
  const std::uint32_t cx = cell_id[slot] & 0xFFFFu, cy = cell_id[slot] >> 16;
  std::uint32_t last = cy << 16 | cx;
  bool crossed_ground = false;
  for (int step = 1; step <= b.steps; ++step) {
    const float qx = px + sign * static_cast<float>(step) * ux + b.range;
    const float qy = py + sign * static_cast<float>(step) * uy + b.range;
    if (qx < 0 || qy < 0) break;
    const auto ix = static_cast<std::uint32_t>(qx * b.inv_cell),
               iy = static_cast<std::uint32_t>(qy * b.inv_cell);
    if (ix >= side || iy >= side) break;
    if ((iy << 16 | ix) == last) continue;
    last = iy << 16 | ix;
    const std::size_t d = s.dense(ix, iy);
    if (!State::test(s.seen, d)) continue;  // nothing seen here: keep walking
    // Not open: only ground seen, or already in a component. Only ground may be walked
    // over (overhangs on); else the walk ends here without the cell's slot (a cache miss).
    if (b.overhang <= 0 && !State::test(s.open, d)) break;
    const std::uint32_t other = s.slot_of[d];
    if (s.label[other] == kNone && s.obstacle_count[other] == 0) {
      // Only ground seen here: with overhangs on, walk on (checked at the far end).
      if (b.overhang > 0) {
        crossed_ground = true;
        continue;
      }
      break;
    }
    // Ground crossed: the nearer of the two cells must be an overhang (its lowest
    // obstacle point at least overhang above the ground), so the ground was seen under it.
    const std::uint32_t nearer = sign > 0 ? slot : other;
    const float gap = s.band_min[nearer] - s.ground_at[nearer];
    const bool under = !crossed_ground || (gap >= b.overhang && gap <= b.overhang_top);
    if (under && s.label[other] == kUnvisited && s.overhead[other] == s.overhead[slot] &&
        std::fabs(s.band_max[other] - s.band_max[slot]) <=
            (crossed_ground ? b.overhang_height : b.height)) {
      s.label[other] = comp;
      State::unset(s.open, d);
      s.depth[other] = 0;
      (void)s.component_cells.push_back(other);
    }
    break;
  }
}

// The component in parts: split at its people when it may be (not too large as a whole, not
// smaller than a person on both sides), else one part, the whole.
void Segmenter::State::divide(const Part& whole, std::uint32_t comp,
                              const SegmenterConfig& c) noexcept {
  const double max_extent_cells = c.max_segment_extent_m / c.cell_m;
  const float split_height = static_cast<float>(c.split_height_m);
  const auto person_cells = static_cast<std::uint32_t>(c.split_person_m / c.cell_m + 1e-9);
  // Too large as a whole (a building, a long wall): dropped whole, not split.
  const bool too_large = whole.points > c.max_segment_points ||
                         (whole.x1 - whole.x0 + 1) > max_extent_cells ||
                         (whole.y1 - whole.y0 + 1) > max_extent_cells;
  // Smaller than a person on both sides: one object, nothing to split.
  const bool too_small = whole.x1 - whole.x0 < person_cells && whole.y1 - whole.y0 < person_cells;
  if (split_height > 0 && !too_large && !too_small && split(comp, c)) return;
  parts.clear();
  Part* one = parts.append();  // capacity max_segments + 1 >= 2
  *one = whole;
  for (const std::uint32_t slot : component_cells) part[slot] = 0;
}

// Keeps or drops each part; the kept parts' cells get their points' offsets.
void Segmenter::State::keep_parts(const SegmenterConfig& c, Segments& out,
                                  std::uint32_t& cursor) noexcept {
  out.counters.split_segments += parts.size() - 1;
  for (Part& p : parts) keep(p, c, out, cursor);
  for (const std::uint32_t slot : component_cells) {
    Part& p = parts[part[slot]];
    if (p.first == kNone) continue;
    offset[slot] = p.first;
    p.first += obstacle_count[slot];
  }
}

// Keeps a part as a segment or counts why not; its points go to [first, first + points).
void Segmenter::State::keep(Part& p, const SegmenterConfig& c, Segments& out,
                            std::uint32_t& cursor) noexcept {
  SegmentCounters& k = out.counters;
  const double max_extent_cells = c.max_segment_extent_m / c.cell_m;
  if (p.points < c.min_segment_points) {
    ++k.dropped_too_small;
    return;
  }
  if (p.points > c.max_segment_points || (p.x1 - p.x0 + 1) > max_extent_cells ||
      (p.y1 - p.y0 + 1) > max_extent_cells) {
    ++k.dropped_too_large;
    return;
  }
  Segment* seg = out.segments.append();
  if (seg == nullptr || cursor + p.points > out.point_indices.capacity()) {
    if (seg != nullptr) out.segments.pop_back();
    ++k.dropped_segment_overflow;
    return;
  }
  *seg = Segment{};
  seg->first = cursor;
  seg->count = static_cast<std::uint32_t>(p.points);
  seg->cells = p.cells;
  p.first = cursor;
  cursor += seg->count;
}

// Points of weak cells no obstacle reached are ground (a low bump: curb edge, camber).
void Segmenter::State::count_cells(SegmentCounters& k) const noexcept {
  for (std::size_t slot = 0; slot < occupied; ++slot) {
    if (label[slot] == kNone) continue;
    if (label[slot] == kWeak) {
      k.ground_points += obstacle_count[slot];
    } else {
      ++k.obstacle_cells;
      k.obstacle_points += obstacle_count[slot];
    }
  }
}

// The fine grid empty again (weak cells no obstacle reached too).
void Segmenter::State::clear_grid() noexcept {
  for (const std::uint32_t id : cell_id) {
    const std::size_t d = dense(id & 0xFFFFu, id >> 16);
    slot_of[d] = kNone;
    open[d >> 6] = 0;
    seen[d >> 6] = 0;
  }
}

// Scatter the point indices of kept segments, contiguous per segment.
void Segmenter::State::scatter(std::size_t count, std::uint32_t cursor, Segments& out) noexcept {
  State& s = *this;
  (void)out.point_indices.resize(cursor);
  for (std::size_t i = 0; i < count; ++i) {
    const std::uint32_t slot = s.point_slot[i];
    if (slot == kNone || s.offset[slot] == kNone) continue;
    out.point_indices[s.offset[slot]++] = static_cast<std::uint32_t>(i);
  }
}

}  // namespace stac::segmentation
