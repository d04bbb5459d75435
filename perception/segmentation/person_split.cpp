// The split at people (docs/segmentation.md): a component's high cells grouped, each
// person-sized group a seed and all other groups one seed together, every cell of the component
// given to its nearest seed, each part a segment.
#include <algorithm>
#include <limits>

#include "perception/segmentation/segmenter_state.hpp"

namespace stac::segmentation {

// Split of one component (its cells in component_cells, labelled comp) into s.parts, each
// cell's part in s.part; false when it has fewer than two seeds. High cells (top split_height_m
// above the ground) are grouped, linked up to two cells apart so that a missing cell does not
// split a person; each person-sized group is a seed, all other groups one seed together (a car
// cabin, a wall). A breadth-first fill from all seeds at once gives every cell its nearest
// seed over 8-connected cells of the component; cells it does not reach (joined by a ray
// bridge) go to the part whose reached cells' bounds are nearest.
bool Segmenter::State::split(std::uint32_t comp, const SegmenterConfig& c) noexcept {
  parts.clear();
  split_queue.clear();
  if (mark_high_cells(c) == 0) return false;  // no seed
  std::uint32_t shared = kNone;               // the seed of all groups that are not one person
  if (!seed_parts(c, shared)) return false;
  if (parts.size() < 2) return false;
  fill_from_seeds(comp);
  assign_unreached(add_reached_cells(), shared);
  return true;
}

// The component's high cells: part kUnvisited and their bit in `high`, the others part kNone.
// Returns how many are high.
std::uint32_t Segmenter::State::mark_high_cells(const SegmenterConfig& c) noexcept {
  const float split_height = static_cast<float>(c.split_height_m);
  std::uint32_t highs = 0;
  for (const std::uint32_t slot : component_cells) {
    const bool is_high = band_max[slot] - ground_at[slot] >= split_height;
    part[slot] = is_high ? kUnvisited : kNone;
    if (!is_high) continue;
    ++highs;
    State::set(high, dense_of(slot));
  }
  return highs;
}

// Every high cell's bit is cleared when it joins a group; on an early return the rest are.
bool Segmenter::State::seed_parts(const SegmenterConfig& c, std::uint32_t& shared) noexcept {
  const auto person_cells = static_cast<std::uint32_t>(c.split_person_m / c.cell_m + 1e-9);
  std::uint32_t persons = 0;
  for (const std::uint32_t start : component_cells) {
    if (part[start] != kUnvisited) continue;
    const std::size_t begin = split_queue.size();
    const Part group = grow_high_group(start);
    const bool person = group.points >= c.split_min_points && group.x1 - group.x0 < person_cells &&
                        group.y1 - group.y0 < person_cells &&
                        parts.size() + 1 < parts.capacity();  // room left for `shared`
    // More person-sized groups than a group of people has: foliage (bush tops), left whole.
    if (person && ++persons > kMaxPersons) {
      for (const std::uint32_t slot : component_cells) high[dense_of(slot) >> 6] = 0;
      return false;
    }
    if (!person && shared == kNone) shared = static_cast<std::uint32_t>(parts.size());
    const std::uint32_t seed = person ? static_cast<std::uint32_t>(parts.size()) : shared;
    if (seed == parts.size()) *parts.append() = Part{};  // capacity kept above
    Part& p = parts[seed];
    for (std::size_t i = begin; i < split_queue.size(); ++i) {
      const std::uint32_t id = cell_id[split_queue[i]];
      part[split_queue[i]] = seed;
      p.seed_x += id & 0xFFFFu, p.seed_y += id >> 16, ++p.seed_cells;
    }
  }
  return true;
}

// The group of high cells linked to `start` up to two cells apart, appended to split_queue
// (part kQueued); its points and bounds.
Segmenter::State::Part Segmenter::State::grow_high_group(std::uint32_t start) noexcept {
  State& s = *this;
  const std::uint32_t side = n;  // a local: the stores below cannot change it
  const std::size_t begin = s.split_queue.size();
  State::unset(s.high, s.dense_of(start));
  s.part[start] = kQueued;
  (void)s.split_queue.push_back(start);  // each cell once: never full
  Part group;
  for (std::size_t head = begin; head < s.split_queue.size(); ++head) {
    const std::uint32_t id = s.cell_id[s.split_queue[head]];
    const std::uint32_t cx = id & 0xFFFFu, cy = id >> 16;
    group.add(cx, cy, s.obstacle_count[s.split_queue[head]]);
    for (std::uint32_t yy = cy < 2 ? 0 : cy - 2; yy <= std::min(cy + 2, side - 1); ++yy) {
      for (std::uint32_t xx = cx < 2 ? 0 : cx - 2; xx <= std::min(cx + 2, side - 1); ++xx) {
        const std::size_t d = s.dense(xx, yy);
        if (!State::test(s.high, d)) continue;  // not a high cell of comp left to group
        State::unset(s.high, d);
        const std::uint32_t other = s.slot_of[d];
        s.part[other] = kQueued;
        (void)s.split_queue.push_back(other);
      }
    }
  }
  return group;
}

// Breadth first from all seeds at once over the component's 8-connected cells: each cell
// reached takes the part of the cell it was reached from.
void Segmenter::State::fill_from_seeds(std::uint32_t comp) noexcept {
  State& s = *this;
  const std::uint32_t side = n;  // a local: the stores below cannot change it
  for (std::size_t head = 0; head < s.split_queue.size(); ++head) {
    const std::uint32_t slot = s.split_queue[head];
    const std::uint32_t id = s.cell_id[slot];
    const std::uint32_t cx = id & 0xFFFFu, cy = id >> 16;
    for (std::uint32_t yy = cy == 0 ? 0 : cy - 1; yy <= std::min(cy + 1, side - 1); ++yy) {
      for (std::uint32_t xx = cx == 0 ? 0 : cx - 1; xx <= std::min(cx + 1, side - 1); ++xx) {
        const std::uint32_t other = s.slot_of[s.dense(xx, yy)];
        if (other == kNone || s.label[other] != comp || s.part[other] != kNone) continue;
        s.part[other] = s.part[slot];
        (void)s.split_queue.push_back(other);
      }
    }
  }
}

// The cells the fill reached first; the others (each once: after the reached ones in
// split_queue, which holds every cell of the component at most once) wait for the bounds.
std::size_t Segmenter::State::add_reached_cells() noexcept {
  const std::size_t reached = split_queue.size();
  for (const std::uint32_t slot : component_cells) {
    if (part[slot] == kNone) {
      (void)split_queue.push_back(slot);
      continue;
    }
    const std::uint32_t id = cell_id[slot];
    parts[part[slot]].add(id & 0xFFFFu, id >> 16, obstacle_count[slot]);
  }
  return reached;
}

// A cell not 8-connected to any seed goes to the part whose reached cells' bounds are
// nearest, ties to the nearest seed centre. A person's part takes such a cell only within
// kPersonReach cells of its bounds when there is a shared part: a bicyclist passing a
// parked car shadows the car's side, and the pieces of the side left between the shadows,
// bridged to the rider's wheels along their rays, are nearer the rider than the car's
// cabin. The bounds are those of the reached cells, so the order of these cells does not
// matter.
void Segmenter::State::assign_unreached(std::size_t reached, std::uint32_t shared) noexcept {
  constexpr std::uint64_t kPersonReach = 2;
  const std::size_t parts_n = parts.size();
  for (std::size_t q = reached; q < split_queue.size(); ++q) {
    const std::uint32_t slot = split_queue[q];
    const std::uint32_t id = cell_id[slot];
    const std::uint32_t cx = id & 0xFFFFu, cy = id >> 16;
    std::uint64_t best_box = std::numeric_limits<std::uint64_t>::max();
    double best_centre = std::numeric_limits<double>::infinity();
    std::uint32_t best = 0;
    for (std::uint32_t i = 0; i < parts_n; ++i) {
      const Part& p = parts[i];
      const std::uint64_t gx = cx < p.x0 ? p.x0 - cx : (cx > p.x1 ? cx - p.x1 : 0);
      const std::uint64_t gy = cy < p.y0 ? p.y0 - cy : (cy > p.y1 ? cy - p.y1 : 0);
      const std::uint64_t box = gx * gx + gy * gy;  // an empty part: x0 = kNone, far
      if (i != shared && shared != kNone && box > kPersonReach * kPersonReach) continue;
      const double dx = p.seed_x / p.seed_cells - cx, dy = p.seed_y / p.seed_cells - cy;
      const double centre = dx * dx + dy * dy;
      if (box < best_box || (box == best_box && centre < best_centre)) {
        best_box = box, best_centre = centre, best = i;
      }
    }
    part[slot] = best;
  }
  for (std::size_t q = reached; q < split_queue.size(); ++q) {
    const std::uint32_t slot = split_queue[q];
    const std::uint32_t id = cell_id[slot];
    parts[part[slot]].add(id & 0xFFFFu, id >> 16, obstacle_count[slot]);
  }
}

}  // namespace stac::segmentation
