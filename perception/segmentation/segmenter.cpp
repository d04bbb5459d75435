// The segmenter (docs/segmentation.md): its configuration checked, its buffers allocated, and
// one scan's steps in order; each step is in the file of its part (segmenter_state.hpp).
#include "perception/segmentation/segmenter.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "perception/segmentation/segmenter_state.hpp"

namespace stac::segmentation {
namespace {

std::uint32_t cells_across(double range_m, double cell_m) {
  return static_cast<std::uint32_t>(std::ceil(2.0 * range_m / cell_m));
}

}  // namespace

const char* validate(const SegmenterConfig& c) noexcept {
  if (!(c.cell_m >= 0.02 && c.cell_m <= 5.0)) return "cell_m must be in [0.02, 5] m";
  if (!(c.range_m > 0 && c.range_m <= 500)) return "range_m must be in (0, 500] m";
  if (!(c.min_range_m >= 0 && c.min_range_m < c.range_m))
    return "min_range_m must be in [0, range_m)";
  if (cells_across(c.range_m, c.cell_m) > 8192)
    return "2 x range_m / cell_m gives a grid over 8192 cells across (its map alone would take "
           "over 256 MB)";
  if (!(c.sensor_height_m >= 0 && c.sensor_height_m <= 10))
    return "sensor_height_m must be in [0, 10] m";
  if (!(c.below_ground_m >= 0)) return "below_ground_m must be >= 0 m";
  if (!(c.below_ground_slope >= 0 && c.below_ground_slope <= 1))
    return "below_ground_slope must be in [0, 1] m/m";
  if (!(c.ground_cell_m >= c.cell_m && c.ground_cell_m <= 20))
    return "ground_cell_m must be in [cell_m, 20] m";
  if (!(c.ground_radius_m >= 0 && c.ground_radius_m <= 20))
    return "ground_radius_m must be in [0, 20] m";
  if (!(c.ground_max_slope >= 0 && c.ground_max_slope <= 1))
    return "ground_max_slope must be in [0, 1] m/m";
  if (!(c.ground_clearance_m >= 0)) return "ground_clearance_m must be >= 0 m";
  if (!(c.obstacle_height_m > c.ground_clearance_m))
    return "obstacle_height_m must be > ground_clearance_m";
  if (!(c.obstacle_spread_m > 0)) return "obstacle_spread_m must be > 0 m";
  if (!(c.max_height_m > c.obstacle_height_m)) return "max_height_m must be > obstacle_height_m";
  if (c.weak_join_cells > 10) return "weak_join_cells must be in 0..10";
  if (!(c.bridge_m >= 0 && c.bridge_m <= 10)) return "bridge_m must be in [0, 10] m";
  if (!(c.bridge_height_m >= 0)) return "bridge_height_m must be >= 0 m";
  if (!(c.overhang_m >= 0 && c.overhang_m <= c.max_height_m))
    return "overhang_m must be in [0, max_height_m] m";
  if (!(c.overhang_max_m >= c.overhang_m)) return "overhang_max_m must be >= overhang_m";
  if (!(c.overhang_height_m >= 0)) return "overhang_height_m must be >= 0 m";
  if (!(c.overhead_m == 0 ||
        (c.overhead_m > c.obstacle_height_m && c.overhead_m <= c.max_height_m)))
    return "overhead_m must be 0 (off) or in (obstacle_height_m, max_height_m] m";
  if (!(c.split_height_m == 0 ||
        (c.split_height_m > c.obstacle_height_m && c.split_height_m <= c.max_height_m)))
    return "split_height_m must be 0 (off) or in (obstacle_height_m, max_height_m] m";
  if (!(c.split_person_m >= c.cell_m && c.split_person_m <= c.max_segment_extent_m))
    return "split_person_m must be in [cell_m, max_segment_extent_m] m";
  if (c.split_min_points < 1) return "split_min_points must be >= 1";
  if (c.min_segment_points < 1) return "min_segment_points must be >= 1";
  if (c.max_segment_points < c.min_segment_points)
    return "max_segment_points must be >= min_segment_points";
  if (!(c.max_segment_extent_m > 0)) return "max_segment_extent_m must be > 0 m";
  if (c.box_fit_points > 100'000) return "box_fit_points must be in [0, 100000]";
  if (!(c.box_fit_min_length_m >= 0 && c.box_fit_min_length_m <= 1000))
    return "box_fit_min_length_m must be in [0, 1000] m";
  // Capacities: allocated at construction, so bounded (a scan of the HDL-64E has at most about
  // 0.9 million returns, dual return at 5 Hz).
  if (c.max_points < 1 || c.max_points > 10'000'000) return "max_points must be in 1..10000000";
  if (c.max_occupied_cells < 1 || c.max_occupied_cells > 4'194'304)
    return "max_occupied_cells must be in 1..4194304";
  if (c.max_segments < 1 || c.max_segments > 1'000'000) return "max_segments must be in 1..1000000";
  return "";
}

Segmenter::State::State(const SegmenterConfig& c)
    : n(cells_across(c.range_m, c.cell_m)),
      m(cells_across(c.range_m, c.ground_cell_m)),
      tiles((n + 7) / 8),
      slot_of(std::size_t{tiles} * tiles * 64, kNone),
      open(std::size_t{tiles} * tiles, 0),
      high(std::size_t{tiles} * tiles, 0),
      seen(std::size_t{tiles} * tiles, 0),
      pad(static_cast<std::uint32_t>(std::ceil(c.ground_radius_m / c.ground_cell_m))),
      mp(m + 2 * pad),
      ground_min(std::size_t{mp} * mp, std::numeric_limits<float>::infinity()),
      ground_min2(std::size_t{mp} * mp, 0.0f),
      ground(std::size_t{mp} * mp, 0.0f),
      ground_cells(std::size_t{mp} * mp),
      coarse_column(n),
      coarse_row(n),
      point_slot(c.max_points),
      point_z(c.max_points),
      cell_id(c.max_occupied_cells),
      coarse_id(c.max_occupied_cells),
      z_min(c.max_occupied_cells),
      ground_at(c.max_occupied_cells),
      band_max(c.max_occupied_cells),
      band_min(c.max_occupied_cells),
      obstacle_count(c.max_occupied_cells),
      label(c.max_occupied_cells),
      offset(c.max_occupied_cells),
      depth(c.max_occupied_cells),
      overhead(c.max_occupied_cells),
      component_cells(c.max_occupied_cells),
      part(c.max_occupied_cells),
      split_queue(c.max_occupied_cells),
      parts(c.max_segments + 1),
      fit_x(c.box_fit_points + 3),  // + 3: padded to a multiple of four (fit_heading)
      fit_y(c.box_fit_points + 3) {}

Segmenter::Segmenter(const SegmenterConfig& config) : config_(config) {
  if (const char* why = validate(config); *why != '\0') {
    throw std::invalid_argument(std::string("segmentation: ") + why);
  }
  state_ = std::make_unique<State>(config);
  for (std::uint32_t i = 0; i < state_->n; ++i) {
    const double centre = (i + 0.5) * config.cell_m;
    const auto g =
        std::min(static_cast<std::uint32_t>(centre / config.ground_cell_m), state_->m - 1);
    state_->coarse_column[i] = g + state_->pad;
    state_->coarse_row[i] = (g + state_->pad) * state_->mp;
  }
  const int r = static_cast<int>(std::ceil(config.ground_radius_m / config.ground_cell_m));
  for (int dy = -r; dy <= r; ++dy) {
    for (int dx = -r; dx <= r; ++dx) {
      const double d = std::hypot(dx, dy) * config.ground_cell_m;
      if (d <= config.ground_radius_m + 1e-9) {
        state_->window.push_back({static_cast<std::ptrdiff_t>(dy) * state_->mp + dx,
                                  static_cast<float>(d * config.ground_max_slope)});
      }
    }
  }
}

Segmenter::Segmenter(Segmenter&&) noexcept = default;
Segmenter& Segmenter::operator=(Segmenter&&) noexcept = default;
Segmenter::~Segmenter() = default;

Segments Segmenter::make_segments() const {
  return Segments(config_.max_segments, config_.max_points);
}

void Segmenter::segment(const PointView& points, Segments& out) noexcept {
  State& s = *state_;
  const SegmenterConfig& c = config_;
  out.segments.clear();
  out.point_indices.clear();
  out.counters = SegmentCounters{};
  SegmentCounters& k = out.counters;
  k.points_in = points.count;
  const std::size_t count = std::min(points.count, std::min(c.max_points, s.point_slot.capacity()));
  k.ignored_over_capacity = points.count - count;
  s.bin_points(points, count, c, k);
  s.local_ground();
  s.classify_points(count, c, k);
  s.mark_obstacle_cells(c);
  const std::uint32_t kept_points = s.flood_fill(c, out);
  s.scatter(count, kept_points, out);
  s.describe(points, c, out);
}

}  // namespace stac::segmentation
