// Multi-object tracker on segment centroids in the world frame (thesis ch. 1): one linear Kalman
// filter per track (constant velocity in x,y; z position only), gated association solved
// globally (Hungarian), tentative -> confirmed -> coasting -> deleted, stable ids never reused.
// Everything is allocated by the constructor; update() never allocates.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "perception/tracking/assignment.hpp"
#include "perception/tracking/track.hpp"
#include "perception/tracking/tracker_config.hpp"
#include "rt/fixed_vector.hpp"

namespace stac::tracking {

// One segment of a scan, in the world frame (the caller applies the ego pose).
struct Detection {
  Eigen::Vector3f centroid = Eigen::Vector3f::Zero();  // m
  // x,y centre of the oriented box (m); NaN when the caller has none (the centroid stands in).
  Eigen::Vector2f box_center = Eigen::Vector2f::Constant(std::numeric_limits<float>::quiet_NaN());
  float length = 0, width = 0, height = 0;  // oriented box, m
  float yaw = 0;                            // box heading, rad (mod pi)
  std::uint32_t points = 0;
  std::uint32_t segment = 0;  // index of the segment it came from
  bool end_on = false;        // completed by complete_end_on: the near end (a face) was seen

  // The x,y position the tracker measures: the box centre (position_from_box) or the centroid.
  [[nodiscard]] Eigen::Vector2f position(bool from_box) const noexcept {
    return from_box && box_center.allFinite() ? box_center : centroid.head<2>();
  }
};

// Cumulative counters since construction (overflow and anomalies, never silent).
struct TrackerCounters {
  std::uint64_t scans = 0;
  std::uint64_t spawned = 0;
  std::uint64_t deleted_uncertain = 0;    // position uncertainty passed life.max_position_std_m
  std::uint64_t deleted_coasting = 0;     // missed more than life.max_coast_scans
  std::uint64_t deleted_tentative = 0;    // tentative track missed
  std::uint64_t pool_overflow = 0;        // detections that could not spawn: pool full
  std::uint64_t dropped_detections = 0;   // beyond max_detections
  std::uint64_t invalid_detections = 0;   // non-finite centroid: neither matched nor spawned
  std::uint64_t stamp_regressions = 0;    // scan stamp not after the previous one (no predict)
  std::uint64_t solver_failures = 0;      // scans with a component's assignment refused
                                          // (non-finite costs): no matches in that component
  std::uint64_t absorbed_detections = 0;  // fragments joined to a matched track's measurement
  std::uint64_t deleted_merged = 0;       // younger tracks of fragments merged into an older one
  std::uint64_t deleted_overlap = 0;      // younger tracks inside an older track's box
  std::uint64_t anchored_detections = 0;  // measured as the visible end of a known tall body
};

// Caller-owned result of one update: every live track (deleted ones are gone).
struct TrackerOutput {
  explicit TrackerOutput(std::size_t max_tracks) : tracks(max_tracks) {}
  std::int64_t stamp_ns = 0;
  rt::FixedVector<Track> tracks;
  TrackerCounters counters;  // copy of the tracker's counters after this update
};

// Applies the end-on completion (TrackerConfig::end_on_*) to a detection seen from `sensor_xy`
// (world x,y of the sensor, m): moves its box centre away from the sensor and sets its length.
// Returns whether it did. Detections without a box centre are left alone.
bool complete_end_on(const TrackerConfig& config, const Eigen::Vector2f& sensor_xy,
                     Detection& d) noexcept;

class Tracker {
 public:
  explicit Tracker(const TrackerConfig& config);  // throws std::invalid_argument on bad config
  ~Tracker();
  Tracker(const Tracker&) = delete;
  Tracker& operator=(const Tracker&) = delete;

  // One scan: predict every track to stamp_ns, associate, update, spawn, prune, report.
  // out.tracks must have capacity >= config.max_tracks (else it is filled up to its capacity).
  // sensor_xy: the sensor's x,y in the frame of the detections, for the occlusion of a known
  // body's ends (TrackerConfig::body.gating); nullptr: unknown, never tested.
  void update(std::int64_t stamp_ns, std::span<const Detection> detections, TrackerOutput& out,
              const Eigen::Vector2f* sensor_xy = nullptr) noexcept;

  [[nodiscard]] const TrackerConfig& config() const noexcept { return config_; }
  [[nodiscard]] const TrackerCounters& counters() const noexcept { return counters_; }
  [[nodiscard]] std::size_t live_tracks() const noexcept { return live_.size(); }

 private:
  struct Slot;  // slot.hpp
  struct Gated {
    std::size_t rows = 0, cols = 0;  // tracks and detections with an allowed pair
  };
  // The steps of update(), in order.
  void predict_all(std::int64_t stamp_ns) noexcept;
  // Gates every (track, detection) pair into pair_cost_, listing the rows and columns with an
  // allowed pair in rows_ and cols_ (association.cpp).
  Gated gate(std::span<const Detection> detections) noexcept;
  // learns_extent: d may lengthen the track's known extent (not a union made inside that body).
  void correct(Slot& s, const Detection& d, std::int64_t stamp_ns, bool learns_extent,
               const Eigen::Matrix2d* spread = nullptr, bool single = false) noexcept;
  bool spawn(const Detection& d, std::int64_t stamp_ns) noexcept;  // false: not spawned (counted)
  void absorb_fragments(std::span<const Detection> detections) noexcept;
  // The steps of absorb_fragments (fragments.cpp).
  struct HostChoice;
  void start_merged(std::span<const Detection> detections) noexcept;
  HostChoice find_host(std::size_t fi, const Detection& f, const Slot* own, std::size_t nd,
                       float max_gap, float reach_sq) const noexcept;
  void try_union(std::size_t hi, const Detection& f, bool narrow_host,
                 HostChoice& c) const noexcept;
  // Whether fragment f lies wholly inside the known body of track slot s
  // (fragments.known_margin_m).
  [[nodiscard]] bool inside_known_body(const Slot& s, const Detection& f) const noexcept;
  // Of piece d of track s's known body, spanning [u0, u1] along the track's heading about its
  // prediction, at vc across: 1 when only the low end is hidden from the sensor by a nearer
  // detection (not a piece of the same body), 2 when only the high end is, else 0.
  [[nodiscard]] int hidden_end(const Slot& s, const Detection& d, float u0, float u1,
                               float vc) const noexcept;
  // Whether measurement m (of detection di) is a piece of track s's known body (piece_of_body in
  // tracker.cpp, with s's known extent and hidden_end): its spread, distance gap and the body's
  // centre it measures.
  [[nodiscard]] bool piece(const Slot& s, const Detection& m, std::size_t di,
                           Eigen::Matrix2d& spread, float& gap,
                           Eigen::Vector2f& centre) const noexcept;
  void correct_matched(std::int64_t stamp_ns, std::size_t nd) noexcept;
  void prune() noexcept;
  void spawn_unmatched(std::int64_t stamp_ns, std::span<const Detection> detections) noexcept;
  void merge_overlapping(std::int64_t stamp_ns) noexcept;
  // The steps of merge_overlapping (fragments.cpp).
  struct GrownBox;
  [[nodiscard]] bool x_before(std::uint32_t p, std::uint32_t q) const noexcept;
  void move_to_place(std::uint32_t t) noexcept;
  void merge_into(std::size_t i, std::int64_t stamp_ns) noexcept;
  bool try_merge(std::size_t i, std::size_t j, GrownBox& g, std::int64_t stamp_ns) noexcept;
  void report(std::int64_t stamp_ns, TrackerOutput& out) noexcept;
  // Solves the assignment of the gated rows_ x cols_ (pair_cost_, nd detections per track) per
  // connected component of the allowed pairs into det_match_.
  void assign(std::size_t nd, std::size_t nrows, std::size_t ncols) noexcept;

  TrackerConfig config_;
  TrackerCounters counters_;
  std::vector<Slot> slots_;              // the pool
  rt::FixedVector<std::uint32_t> live_;  // slots in use
  rt::FixedVector<std::uint32_t> free_;  // slots free
  // Association workspace, rows = gated tracks, cols = gated detections.
  AssignmentSolver solver_;
  std::vector<double> cost_;
  std::vector<int> row_to_col_;
  std::vector<std::int32_t> det_match_;     // per detection: slot or -1
  std::vector<std::uint32_t> rows_, cols_;  // compact index -> live index / detection index
  std::vector<std::int32_t> col_of_det_;
  std::vector<Eigen::Vector2d> positions_;         // per detection: its measured x,y
  std::vector<Eigen::Vector2d> track_xy_;          // per live index: its x,y (overlap merge)
  std::vector<std::uint32_t> order_, rank_;        // live indices sorted by x; each one's rank
  std::vector<std::uint32_t> candidate_;           // live indices within a track's reach
  std::vector<std::uint32_t> parent_, component_;  // per row, then column: union-find, component
  std::vector<std::uint32_t> component_start_;     // per component: its rows', columns' start
  std::vector<std::uint32_t> component_members_;   // rows, columns, grouped by component
  std::vector<float> pair_cost_;            // live x detections: squared Mahalanobis, < 0 gated out
  std::vector<Detection> merged_;           // per detection: its measurement, fragments joined
  std::vector<std::uint8_t> host_;          // per detection: 1 when it absorbed a fragment
  std::vector<std::uint8_t> merged_track_;  // per live index: merged into another, delete
  std::span<const Detection> scan_;         // this scan's detections (during update)
  Eigen::Vector2f sensor_xy_ = Eigen::Vector2f::Zero();
  bool have_sensor_ = false;
  std::uint64_t next_id_ = 1;
  std::int64_t last_stamp_ns_ = 0;
  bool have_stamp_ = false;
};

}  // namespace stac::tracking
