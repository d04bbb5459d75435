#include "perception/segmentation/segmenter.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace stac::segmentation {
namespace {

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
constexpr std::uint32_t kUnvisited = kNone - 1;  // an obstacle cell not yet in a component
constexpr std::uint32_t kWeak = kNone - 2;       // points above the clearance, but low: joins a
                                                 // component it touches, never starts one
constexpr std::uint32_t kMaxPersons = 8;         // split: more person-sized groups are foliage
constexpr std::uint32_t kQueued = kNone - 2;     // split: a high cell in the group being grown

// A part of a component (the whole of it, or its cells nearest one seed when it is split).
struct Part {
  std::uint64_t points = 0;
  std::uint32_t cells = 0;
  std::uint32_t x0 = kNone, x1 = 0, y0 = kNone, y1 = 0;  // cell bounds
  double seed_x = 0, seed_y = 0;                         // sums of its seed cells' ix, iy
  std::uint32_t seed_cells = 0;
  std::uint32_t first = kNone;  // next point offset when kept, else kNone

  void add(std::uint32_t ix, std::uint32_t iy, std::uint32_t count) noexcept {
    points += count;
    ++cells;
    x0 = std::min(x0, ix), x1 = std::max(x1, ix), y0 = std::min(y0, iy), y1 = std::max(y1, iy);
  }
};

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

// The dense fine grid maps a cell to its slot (kNone when empty) and is reset cell by cell after
// each scan; it is stored in 8 x 8 tiles so that the neighbouring returns of a ring hit the same
// cache lines. The coarse ground grid is reset the same way. Per occupied cell the data
// sits in compact "slot" arrays in the order the cells were first hit.
struct Segmenter::State {
  explicit State(const SegmenterConfig& c)
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
  void bin_points(const PointView& points, std::size_t count, const SegmenterConfig& c,
                  SegmentCounters& k) noexcept;
  void local_ground() noexcept;
  void classify_points(std::size_t count, const SegmenterConfig& c, SegmentCounters& k) noexcept;
  void mark_obstacle_cells(const SegmenterConfig& c) noexcept;
  // Returns the points of the kept segments.
  std::uint32_t flood_fill(const SegmenterConfig& c, Segments& out) noexcept;
  bool split(std::uint32_t comp, const SegmenterConfig& c) noexcept;
  void keep(Part& p, const SegmenterConfig& c, Segments& out, std::uint32_t& cursor) noexcept;
  void scatter(std::size_t count, std::uint32_t cursor, Segments& out) noexcept;
  void describe(const PointView& points, const SegmenterConfig& c, Segments& out) noexcept;
};

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

namespace {

// L-shape fitting's rectangle search (SegmenterConfig::box_fit_points): the heading in
// [-5, 95) degrees whose rectangle the points lie closest to the edges of, by the closeness
// criterion (sum over the points of 1 / max(distance to the nearer edge, 1 cm)), searched every
// 6 degrees and then every degree within 5 of the best, over up to `cap` of the points (evenly
// strided) about (mx, my).
double fit_heading(const PointView& points, std::span<const std::uint32_t> indices, double mx,
                   double my, float* fx, float* fy, std::size_t cap) noexcept {
  const std::size_t n = indices.size();
  const std::size_t stride = (n + cap - 1) / cap;
  std::size_t m = 0;
  for (std::size_t k = 0; k < n && m < cap; k += stride) {
    float x, y, z;
    points.read(indices[k], x, y, z);
    fx[m] = static_cast<float>(x - mx);
    fy[m] = static_cast<float>(y - my);
    ++m;
  }
  // The score of one heading, four points at a time where SSE is there (the x86-64 baseline):
  // the same rectangle, the sum in another order (four partial sums).
  constexpr float kMinDistance = 0.01f;
#if defined(__SSE2__)
  // Pads to a multiple of four with copies of the first point: no change to the rectangle;
  // their terms are masked out of the sum.
  const std::size_t m4 = (m + 3) / 4 * 4;
  for (std::size_t i = m; i < m4; ++i) fx[i] = fx[0], fy[i] = fy[0];
  const auto closeness = [&](double yaw) {
    const auto ca = static_cast<float>(std::cos(yaw)), sa = static_cast<float>(std::sin(yaw));
    const __m128 c = _mm_set1_ps(ca), sn = _mm_set1_ps(sa), ns = _mm_set1_ps(-sa);
    __m128 u0 = _mm_set1_ps(std::numeric_limits<float>::infinity());
    __m128 u1 = _mm_set1_ps(-std::numeric_limits<float>::infinity()), v0 = u0, v1 = u1;
    for (std::size_t i = 0; i < m4; i += 4) {
      const __m128 x = _mm_loadu_ps(fx + i), y = _mm_loadu_ps(fy + i);
      const __m128 u = _mm_add_ps(_mm_mul_ps(c, x), _mm_mul_ps(sn, y));
      const __m128 v = _mm_add_ps(_mm_mul_ps(ns, x), _mm_mul_ps(c, y));
      u0 = _mm_min_ps(u0, u), u1 = _mm_max_ps(u1, u), v0 = _mm_min_ps(v0, v),
      v1 = _mm_max_ps(v1, v);
    }
    // Across the lanes.
    const auto reduce = [](__m128 a, auto op) {
      a = op(a, _mm_shuffle_ps(a, a, _MM_SHUFFLE(1, 0, 3, 2)));
      return op(a, _mm_shuffle_ps(a, a, _MM_SHUFFLE(2, 3, 0, 1)));
    };
    const auto min = [](__m128 a, __m128 b) { return _mm_min_ps(a, b); };
    const auto max = [](__m128 a, __m128 b) { return _mm_max_ps(a, b); };
    u0 = reduce(u0, min), u1 = reduce(u1, max), v0 = reduce(v0, min), v1 = reduce(v1, max);
    const __m128 floor = _mm_set1_ps(kMinDistance), one = _mm_set1_ps(1.0f);
    __m128 sum = _mm_setzero_ps();
    for (std::size_t i = 0; i < m4; i += 4) {
      const __m128 x = _mm_loadu_ps(fx + i), y = _mm_loadu_ps(fy + i);
      const __m128 u = _mm_add_ps(_mm_mul_ps(c, x), _mm_mul_ps(sn, y));
      const __m128 v = _mm_add_ps(_mm_mul_ps(ns, x), _mm_mul_ps(c, y));
      const __m128 d = _mm_min_ps(_mm_min_ps(_mm_sub_ps(u, u0), _mm_sub_ps(u1, u)),
                                  _mm_min_ps(_mm_sub_ps(v, v0), _mm_sub_ps(v1, v)));
      __m128 term = _mm_div_ps(one, _mm_max_ps(d, floor));
      if (i + 4 > m) {  // the padded lanes of the last four
        alignas(16) float keep[4];
        for (std::size_t l = 0; l < 4; ++l) keep[l] = i + l < m ? 1.0f : 0.0f;
        term = _mm_mul_ps(term, _mm_load_ps(keep));
      }
      sum = _mm_add_ps(sum, term);
    }
    sum = reduce(sum, [](__m128 a, __m128 b) { return _mm_add_ps(a, b); });
    return _mm_cvtss_f32(sum);
  };
#else
  const auto closeness = [&](double yaw) {
    const auto ca = static_cast<float>(std::cos(yaw)), sa = static_cast<float>(std::sin(yaw));
    float u0 = std::numeric_limits<float>::infinity(), u1 = -u0, v0 = u0, v1 = -u0;
    for (std::size_t i = 0; i < m; ++i) {
      const float u = ca * fx[i] + sa * fy[i], v = -sa * fx[i] + ca * fy[i];
      u0 = std::min(u0, u), u1 = std::max(u1, u), v0 = std::min(v0, v), v1 = std::max(v1, v);
    }
    float score = 0;
    for (std::size_t i = 0; i < m; ++i) {
      const float u = ca * fx[i] + sa * fy[i], v = -sa * fx[i] + ca * fy[i];
      const float d = std::min(std::min(u - u0, u1 - u), std::min(v - v0, v1 - v));
      score += 1.0f / std::max(d, kMinDistance);
    }
    return score;
  };
#endif
  // Every 6 degrees, then every degree within 5 of the best.
  constexpr double kDegree = M_PI / 180;
  int best_step = 0;
  float best = -1;
  for (int a = 0; a < 90; a += 6) {
    const float score = closeness(a * kDegree);
    if (score > best) best = score, best_step = a;
  }
  const int coarse = best_step;
  for (int a = coarse - 5; a <= coarse + 5; ++a) {
    if (a == coarse) continue;
    const float score = closeness(a * kDegree);
    if (score > best) best = score, best_step = a;
  }
  return best_step * kDegree;
}

}  // namespace

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

// Bin the points: per fine cell its lowest point. First a streaming pass keeps each point's
// dense cell index (kNone when ignored) in point_slot and its z in point_z; then the cells,
// with the grid entry of the point 16 ahead prefetched (slot_of is megabytes: its loads are
// the binning's cost).
void Segmenter::State::bin_points(const PointView& points, std::size_t count,
                                  const SegmenterConfig& c, SegmentCounters& k) noexcept {
  State& s = *this;
  const float range = static_cast<float>(c.range_m);
  const float min_range2 = static_cast<float>(c.min_range_m * c.min_range_m);
  const float inv_cell = static_cast<float>(1.0 / c.cell_m);
  s.ground_cells.clear();
  s.cell_id.clear();
  (void)s.point_slot.resize(count);
  (void)s.point_z.resize(count);
  std::size_t slots = 0;
  const std::size_t max_slots = s.cell_id.capacity();
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
  (void)s.cell_id.resize(slots);
  k.occupied_cells = slots;
  s.occupied = slots;
}

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

// Flood fill 8-connected obstacle cells (a fixed queue, no recursion); keep or drop each.
std::uint32_t Segmenter::State::flood_fill(const SegmenterConfig& c, Segments& out) noexcept {
  State& s = *this;
  const std::uint32_t side = n;  // a local: the stores below cannot change it
  SegmentCounters& k = out.counters;
  const std::size_t slots = s.occupied;
  const float range = static_cast<float>(c.range_m);
  const float inv_cell = static_cast<float>(1.0 / c.cell_m);
  const double max_extent_cells = c.max_segment_extent_m / c.cell_m;
  std::uint32_t cursor = 0;
  std::uint32_t component = 0;
  // Across unseen cells along the sensor's ray: the roof of a car beside the sensor is hit by
  // rings far apart (1 m and more at 8 m) with nothing seen between them (the roof between
  // rings is not sampled, the road under it is hidden). A strong cell links to the first strong
  // cell within bridge_m outward or inward along its ray when every cell crossed is empty and
  // their tops differ by at most bridge_height_m; the first cell where anything was seen ends
  // the walk (a cell of the component itself walks on from there when its turn comes).
  const int bridge_steps = static_cast<int>(c.bridge_m / c.cell_m);  // steps of one cell
  const float bridge_height = static_cast<float>(c.bridge_height_m);
  const float cell = static_cast<float>(c.cell_m);
  const float overhang = static_cast<float>(c.overhang_m);
  const float overhang_height = static_cast<float>(c.overhang_height_m);
  const float overhang_top = static_cast<float>(c.overhang_max_m);
  auto bridge = [&](std::uint32_t slot, std::uint32_t cx, std::uint32_t cy, std::uint32_t comp) {
    const float px = (static_cast<float>(cx) + 0.5f) * cell - range;
    const float py = (static_cast<float>(cy) + 0.5f) * cell - range;
    const float r = std::sqrt(px * px + py * py);
    if (r < cell) return;
    const float ux = cell * px / r, uy = cell * py / r;
    for (const float sign : {1.0f, -1.0f}) {
      std::uint32_t last = cy << 16 | cx;
      bool crossed_ground = false;
      for (int step = 1; step <= bridge_steps; ++step) {
        const float qx = px + sign * static_cast<float>(step) * ux + range;
        const float qy = py + sign * static_cast<float>(step) * uy + range;
        if (qx < 0 || qy < 0) break;
        const auto ix = static_cast<std::uint32_t>(qx * inv_cell),
                   iy = static_cast<std::uint32_t>(qy * inv_cell);
        if (ix >= side || iy >= side) break;
        if ((iy << 16 | ix) == last) continue;
        last = iy << 16 | ix;
        const std::size_t d = s.dense(ix, iy);
        if (!State::test(s.seen, d)) continue;  // nothing seen here: keep walking
        // Not open: only ground seen, or already in a component. Only ground may be walked
        // over (overhangs on); else the walk ends here without the cell's slot (a cache miss).
        if (overhang <= 0 && !State::test(s.open, d)) break;
        const std::uint32_t other = s.slot_of[d];
        if (s.label[other] == kNone && s.obstacle_count[other] == 0) {
          // Only ground seen here: with overhangs on, walk on (checked at the far end).
          if (overhang > 0) {
            crossed_ground = true;
            continue;
          }
          break;
        }
        // Ground crossed: the nearer of the two cells must be an overhang (its lowest
        // obstacle point at least overhang above the ground), so the ground was seen under it.
        const std::uint32_t nearer = sign > 0 ? slot : other;
        const float gap = s.band_min[nearer] - s.ground_at[nearer];
        const bool under = !crossed_ground || (gap >= overhang && gap <= overhang_top);
        if (under && s.label[other] == kUnvisited && s.overhead[other] == s.overhead[slot] &&
            std::fabs(s.band_max[other] - s.band_max[slot]) <=
                (crossed_ground ? overhang_height : bridge_height)) {
          s.label[other] = comp;
          State::unset(s.open, d);
          s.depth[other] = 0;
          (void)s.component_cells.push_back(other);
        }
        break;
      }
    }
  };
  const float split_height = static_cast<float>(c.split_height_m);
  const auto person_cells = static_cast<std::uint32_t>(c.split_person_m / c.cell_m + 1e-9);
  for (std::size_t seed = 0; seed < slots; ++seed) {
    if (s.label[seed] != kUnvisited) continue;  // components start at strong cells only
    // Breadth first: component_cells is the queue. depth: 0 for strong cells, else the weak
    // steps from the nearest strong cell; weak cells spread only up to weak_join_cells deep.
    s.component_cells.clear();
    s.label[seed] = component;
    State::unset(s.open, s.dense_of(static_cast<std::uint32_t>(seed)));
    s.depth[seed] = 0;
    (void)s.component_cells.push_back(static_cast<std::uint32_t>(seed));  // each cell once
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
          s.label[other] = component;
          (void)s.component_cells.push_back(other);
        }
      }
      if (s.depth[slot] == 0 && bridge_steps > 0) bridge(slot, cx, cy, component);
    }
    ++k.clusters;
    // Too large as a whole (a building, a long wall): dropped whole, not split.
    const bool too_large = pts > c.max_segment_points || (x1 - x0 + 1) > max_extent_cells ||
                           (y1 - y0 + 1) > max_extent_cells;
    // Smaller than a person on both sides: one object, nothing to split.
    const bool too_small = x1 - x0 < person_cells && y1 - y0 < person_cells;
    if (!(split_height > 0 && !too_large && !too_small &&
          split(component, c))) {  // one part: the whole
      s.parts.clear();
      Part* whole = s.parts.append();  // capacity max_segments + 1 >= 2
      *whole = Part{pts, static_cast<std::uint32_t>(s.component_cells.size()), x0, x1, y0, y1};
      for (const std::uint32_t slot : s.component_cells) s.part[slot] = 0;
    }
    ++component;
    k.split_segments += s.parts.size() - 1;
    for (Part& p : s.parts) keep(p, c, out, cursor);
    for (const std::uint32_t slot : s.component_cells) {
      Part& p = s.parts[s.part[slot]];
      if (p.first == kNone) continue;
      s.offset[slot] = p.first;
      p.first += s.obstacle_count[slot];
    }
  }

  // Points of weak cells no obstacle reached are ground (a low bump: curb edge, camber).
  for (std::size_t slot = 0; slot < slots; ++slot) {
    if (s.label[slot] == kNone) continue;
    if (s.label[slot] == kWeak) {
      k.ground_points += s.obstacle_count[slot];
    } else {
      ++k.obstacle_cells;
      k.obstacle_points += s.obstacle_count[slot];
    }
  }

  for (const std::uint32_t id : s.cell_id) {  // empty again (weak cells no obstacle reached)
    const std::size_t d = s.dense(id & 0xFFFFu, id >> 16);
    s.slot_of[d] = kNone;
    s.open[d >> 6] = 0;
    s.seen[d >> 6] = 0;
  }
  return cursor;
}

// Split of one component (its cells in component_cells, labelled comp) into s.parts, each
// cell's part in s.part; false when it has fewer than two seeds. High cells (top split_height_m
// above the ground) are grouped, linked up to two cells apart so that a missing cell does not
// split a person; each person-sized group is a seed, all other groups one seed together (a car
// cabin, a wall). A breadth-first fill from all seeds at once gives every cell its nearest
// seed over 8-connected cells of the component; cells it does not reach (joined by a ray
// bridge) go to the part whose reached cells' bounds are nearest.
bool Segmenter::State::split(std::uint32_t comp, const SegmenterConfig& c) noexcept {
  State& s = *this;
  const std::uint32_t side = n;  // a local: the stores below cannot change it
  const float split_height = static_cast<float>(c.split_height_m);
  const auto person_cells = static_cast<std::uint32_t>(c.split_person_m / c.cell_m + 1e-9);
  s.parts.clear();
  s.split_queue.clear();
  std::uint32_t highs = 0;
  for (const std::uint32_t slot : s.component_cells) {
    const bool is_high = s.band_max[slot] - s.ground_at[slot] >= split_height;
    s.part[slot] = is_high ? kUnvisited : kNone;
    if (!is_high) continue;
    ++highs;
    State::set(s.high, s.dense_of(slot));
  }
  if (highs == 0) return false;  // no seed
  // Every high cell's bit is cleared when it joins a group; on an early return the rest are.
  const auto clear_high = [&] {
    for (const std::uint32_t slot : s.component_cells) s.high[s.dense_of(slot) >> 6] = 0;
  };
  std::uint32_t shared = kNone;  // the seed of all groups that are not one person
  std::uint32_t persons = 0;
  for (const std::uint32_t start : s.component_cells) {
    if (s.part[start] != kUnvisited) continue;
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
    const bool person = group.points >= c.split_min_points && group.x1 - group.x0 < person_cells &&
                        group.y1 - group.y0 < person_cells &&
                        s.parts.size() + 1 < s.parts.capacity();  // room left for `shared`
    // More person-sized groups than a group of people has: foliage (bush tops), left whole.
    if (person && ++persons > kMaxPersons) {
      clear_high();
      return false;
    }
    if (!person && shared == kNone) shared = static_cast<std::uint32_t>(s.parts.size());
    const std::uint32_t seed = person ? static_cast<std::uint32_t>(s.parts.size()) : shared;
    if (seed == s.parts.size()) *s.parts.append() = Part{};  // capacity kept above
    Part& p = s.parts[seed];
    for (std::size_t i = begin; i < s.split_queue.size(); ++i) {
      const std::uint32_t id = s.cell_id[s.split_queue[i]];
      s.part[s.split_queue[i]] = seed;
      p.seed_x += id & 0xFFFFu, p.seed_y += id >> 16, ++p.seed_cells;
    }
  }
  if (s.parts.size() < 2) return false;
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
  // The cells the fill reached first; the others (each once: after the reached ones in
  // split_queue, which holds every cell of the component at most once) wait for the bounds.
  const std::size_t reached = s.split_queue.size();
  for (const std::uint32_t slot : s.component_cells) {
    if (s.part[slot] == kNone) {
      (void)s.split_queue.push_back(slot);
      continue;
    }
    const std::uint32_t id = s.cell_id[slot];
    s.parts[s.part[slot]].add(id & 0xFFFFu, id >> 16, s.obstacle_count[slot]);
  }
  // A cell not 8-connected to any seed goes to the part whose reached cells' bounds are
  // nearest, ties to the nearest seed centre. A person's part takes such a cell only within
  // kPersonReach cells of its bounds when there is a shared part: a bicyclist passing a
  // parked car shadows the car's side, and the pieces of the side left between the shadows,
  // bridged to the rider's wheels along their rays, are nearer the rider than the car's
  // cabin. The bounds are those of the reached cells, so the order of these cells does not
  // matter.
  constexpr std::uint64_t kPersonReach = 2;
  const std::size_t parts_n = s.parts.size();
  for (std::size_t q = reached; q < s.split_queue.size(); ++q) {
    const std::uint32_t slot = s.split_queue[q];
    const std::uint32_t id = s.cell_id[slot];
    const std::uint32_t cx = id & 0xFFFFu, cy = id >> 16;
    std::uint64_t best_box = std::numeric_limits<std::uint64_t>::max();
    double best_centre = std::numeric_limits<double>::infinity();
    std::uint32_t best = 0;
    for (std::uint32_t i = 0; i < parts_n; ++i) {
      const Part& p = s.parts[i];
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
    s.part[slot] = best;
  }
  for (std::size_t q = reached; q < s.split_queue.size(); ++q) {
    const std::uint32_t slot = s.split_queue[q];
    const std::uint32_t id = s.cell_id[slot];
    s.parts[s.part[slot]].add(id & 0xFFFFu, id >> 16, s.obstacle_count[slot]);
  }
  return true;
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

// Per segment: centroid, height span, oriented box from the XY principal axis.
void Segmenter::State::describe(const PointView& points, const SegmenterConfig& c,
                                Segments& out) noexcept {
  State& s = *this;
  for (Segment& seg : out.segments) {
    // Sums relative to the first point keep the second moments well conditioned.
    float x0, y0, z0;
    points.read(out.point_indices[seg.first], x0, y0, z0);
    double sx = 0, sy = 0, sz = 0, sxx = 0, sxy = 0, syy = 0;
    float zlo = z0, zhi = z0;
    for (const std::uint32_t i : out.indices(seg)) {
      float x, y, z;
      points.read(i, x, y, z);
      const double dx = x - x0, dy = y - y0;
      sx += dx, sy += dy, sz += z;
      sxx += dx * dx, sxy += dx * dy, syy += dy * dy;
      zlo = std::min(zlo, z), zhi = std::max(zhi, z);
    }
    const double inv = 1.0 / seg.count;
    const double mx = x0 + sx * inv, my = y0 + sy * inv;
    const double cxx = sxx * inv - sx * sx * inv * inv, cxy = sxy * inv - sx * sy * inv * inv,
                 cyy = syy * inv - sy * sy * inv * inv;
    double yaw = 0.5 * std::atan2(2.0 * cxy, cxx - cyy);
    double ca = 0, sa = 0, u0 = 0, u1 = 0, v0 = 0, v1 = 0;
    const auto extents = [&] {  // of the points along yaw and across it, about the centroid
      ca = std::cos(yaw), sa = std::sin(yaw);
      u0 = std::numeric_limits<double>::infinity(), u1 = -u0, v0 = u0, v1 = -u0;
      for (const std::uint32_t i : out.indices(seg)) {
        float x, y, z;
        points.read(i, x, y, z);
        const double dx = x - mx, dy = y - my;
        const double u = ca * dx + sa * dy, v = -sa * dx + ca * dy;
        u0 = std::min(u0, u), u1 = std::max(u1, u), v0 = std::min(v0, v), v1 = std::max(v1, v);
      }
    };
    extents();
    if (c.box_fit_points > 0 && std::max(u1 - u0, v1 - v0) >= c.box_fit_min_length_m) {
      yaw = fit_heading(points, out.indices(seg), mx, my, s.fit_x.data(), s.fit_y.data(),
                        c.box_fit_points);
      extents();
    }
    const double uc = 0.5 * (u0 + u1), vc = 0.5 * (v0 + v1);
    seg.centroid[0] = static_cast<float>(mx);
    seg.centroid[1] = static_cast<float>(my);
    seg.centroid[2] = static_cast<float>(sz * inv);
    seg.z_min = zlo;
    seg.z_max = zhi;
    OrientedBox& b = seg.box;
    b.cx = static_cast<float>(mx + ca * uc - sa * vc);
    b.cy = static_cast<float>(my + sa * uc + ca * vc);
    b.cz = 0.5f * (zlo + zhi);
    b.length = static_cast<float>(u1 - u0);
    b.width = static_cast<float>(v1 - v0);
    b.height = zhi - zlo;
    double box_yaw = yaw;
    if (b.width > b.length) {
      std::swap(b.length, b.width);
      box_yaw += box_yaw > 0 ? -M_PI / 2 : M_PI / 2;
    }
    b.yaw = static_cast<float>(box_yaw);
  }
}

}  // namespace stac::segmentation
