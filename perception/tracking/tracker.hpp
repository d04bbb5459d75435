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

struct TrackerConfig {
  std::size_t max_tracks = 512;       // track pool; spawns beyond it are counted, not made
  std::size_t max_detections = 1024;  // per scan; detections beyond it are dropped and counted
                                      // (each 1..100000, their product at most 2^22)
  // Kalman filter.
  double accel_std_mps2 = 2.0;            // white-noise acceleration in x,y (m/s^2)
  double z_velocity_std_mps = 0.5;        // z random walk (m/s)
  double measurement_std_m = 0.25;        // centroid noise in x,y (m)
  double measurement_z_std_m = 0.3;       // centroid noise in z (m)
  double initial_velocity_std_mps = 6.0;  // velocity std of a new track (m/s)
  // Association: a pair is allowed when both gates pass.
  double gate_mahalanobis_sq = 9.21;  // squared Mahalanobis distance in x,y (chi^2, 2 dof, 99%)
  double gate_distance_m = 3.0;       // Euclidean x,y distance to the prediction (m)
  // Life cycle.
  std::uint32_t confirm_hits = 3;           // hits that make a tentative track confirmed
  std::uint32_t confirm_large_points = 50;  // a hit with a segment this large (points; 0: off)...
  std::uint32_t confirm_large_hits = 2;     // ...confirms after this many hits
  std::uint32_t tentative_max_misses = 1;   // consecutive misses that delete a tentative track
  std::uint32_t max_coast_scans = 20;       // consecutive misses that delete a coasting track
  double max_position_std_m = 1.5;          // sqrt(max eigenvalue of the x,y covariance) (m)
  // Position measured: the oriented box's centre (true) or the points' centroid (false, the
  // thesis). The centroid of a car seen from behind sits on its rear, metres from its centre.
  bool position_from_box = true;
  // Fragments: a detection left unmatched joins the measurement of a track matched in this scan
  // when their boxes are at most absorb_gap_m apart (x,y) and their union fits in
  // absorb_max_length_m x absorb_max_width_m (one car split by the road seen under its body).
  // A younger track matched to such a fragment is merged into the older one (deleted) when
  // their velocities differ by at most absorb_velocity_mps or it is still tentative. People and
  // bicyclists (at most absorb_keep_length_m long, and absorb_keep_width_m wide and at least
  // absorb_keep_height_m tall, or absorb_keep_wide_m wide and at least absorb_keep_wide_height_m
  // tall: people pushing a bike, taller than a sedan's pieces) are never joined to another object;
  // they take only low pieces (under absorb_keep_height_m: legs, a wheel) at most
  // absorb_narrow_gap_m away and stay within those bounds. absorb_gap_m 0: off. A box at least
  // absorb_strip_length_m long and at most absorb_strip_width_m wide is a flat surface (a car's
  // side seen along its length, a wall), never a person (absorb_strip_width_m 0: off).
  // Tall pieces (both at least absorb_tall_height_m high: a truck's cargo box and cab, clipped
  // at the segmenter's max_height_m) may make a union up to absorb_tall_length_m long.
  double absorb_gap_m = 2.0;               // m, box to box
  double absorb_max_length_m = 6.0;        // m
  double absorb_max_width_m = 2.6;         // m
  double absorb_tall_height_m = 2.1;       // m; 0: no longer unions
  double absorb_tall_length_m = 16.5;      // m
  double absorb_velocity_mps = 1.5;        // m/s
  double absorb_keep_length_m = 2.2;       // m
  double absorb_keep_width_m = 1.0;        // m
  double absorb_keep_height_m = 1.0;       // m
  double absorb_narrow_gap_m = 0.3;        // m
  double absorb_keep_wide_m = 1.4;         // m
  double absorb_keep_wide_height_m = 1.6;  // m
  double absorb_strip_length_m = 1.0;      // m
  double absorb_strip_width_m = 0.1;       // m; 0: off
  // A fragment whose own track has at least absorb_established_hits hits is an object of its
  // own (a person beside a car, two cars nose to tail): it is never joined to a car's or a
  // truck's measurement, so absorbing never merges its track (overlap_margin_m still may; 0: off).
  std::uint32_t absorb_established_hits = 10;
  // A track of known extent (extent_memory_length_m) also takes, whatever the gap and the union's
  // width, a fragment that lies wholly inside its body: its known length x its width, about its
  // predicted centre along the heading of its last whole view, grown by absorb_known_margin_m
  // on every side (an end-on face it is matched to is made that body first) (a truck
  // seen as a cab, a cargo box's side and its rear face), person-like pieces included (nobody
  // stands inside a truck). Such a union never lengthens what its track knows (an older track
  // the overlap merge corrects with it still learns from it). < 0: off.
  double absorb_known_margin_m = 0.5;  // m
  // Overlapping tracks: a track whose position lies inside an older track's box grown by
  // overlap_margin_m (neither a person nor a bicyclist, as above, who take only low tracks
  // within absorb_narrow_gap_m) is the same object when both boxes fit in
  // absorb_max_length_m x absorb_max_width_m (absorb_tall_length_m for tall ones, as above): it
  // is merged into the older one, which keeps its
  // id and, when only the younger was measured in this scan, is corrected with the younger's
  // measurement. overlap_margin_m < 0: off.
  double overlap_margin_m = 1.0;  // m
  // End-on vehicles (complete_end_on): a face across the ray end_on_min_width_m..max_width_m
  // wide, at most end_on_max_depth_m deep along it and end_on_min_height_m tall is the rear or
  // front of a vehicle whose body, unseen, extends away from the sensor: its box becomes
  // end_on_length_m long along the ray, when it is at least end_on_min_range_m away (nearer,
  // vehicles show their sides; bicycles seen side-on would pass). end_on_length_m 0: off.
  double end_on_length_m = 4.5;      // m
  double end_on_min_range_m = 15.0;  // m, sensor to box centre
  double end_on_min_width_m = 1.2;   // m, across the ray
  double end_on_max_width_m = 2.7;   // m
  double end_on_max_depth_m = 1.6;   // m, along the ray
  double end_on_min_height_m = 0.0;  // m
  // Known extent of tall vehicles: a track remembers the longest box of its tall measurements
  // (at least absorb_tall_height_m high, fitting absorb_tall_length_m x absorb_max_width_m).
  // Once that is at least extent_memory_length_m, an end-on detection (complete_end_on) along
  // the body's heading (that of its last tall view at least that long and not end-on; within
  // 30 degrees) is the face of that body, not of a car: it is gated, associated and measured
  // (with any fragments joined to it) as the known body extending from the face along that
  // heading, away from the sensor, instead of end_on_length_m along the ray. 0: off.
  double extent_memory_length_m = 6.0;  // m
  // With a known extent, any other tall detection (absorb_tall_height_m) along the track's box
  // (within 30 degrees) that is shorter than the body is a piece of it (a truck's cab, or its
  // cargo box, seen apart): it measures the body's centre at its own box centre, with the
  // variance of where in the body it may lie added (uniform over the slack: (known length - its
  // length)^2 / 12 along the heading, (known width - its width)^2 / 12 across), in the gate, the
  // assignment and the update; the distance gate applies to the nearest centre at which the
  // body covers it. When update() has the sensor's position and exactly one end of the piece is
  // hidden behind a nearer detection, the body's centre is measured half the body's length (the
  // second longest one-segment view) from the other, visible end instead. false: an ordinary
  // detection.
  bool body_gating = true;
  // Box smoothing: weight of the new measurement in the exponential average (0..1].
  double box_smoothing = 0.3;
  // Holistic features: headings of slower smoothed velocities are not differentiated (m/s).
  double min_heading_speed_mps = 0.5;
};

// Cumulative counters since construction (overflow and anomalies, never silent).
struct TrackerCounters {
  std::uint64_t scans = 0;
  std::uint64_t spawned = 0;
  std::uint64_t deleted_uncertain = 0;    // position uncertainty passed max_position_std_m
  std::uint64_t deleted_coasting = 0;     // missed more than max_coast_scans
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
  // body's ends (TrackerConfig::body_gating); nullptr: unknown, never tested.
  void update(std::int64_t stamp_ns, std::span<const Detection> detections, TrackerOutput& out,
              const Eigen::Vector2f* sensor_xy = nullptr) noexcept;

  [[nodiscard]] const TrackerConfig& config() const noexcept { return config_; }
  [[nodiscard]] const TrackerCounters& counters() const noexcept { return counters_; }
  [[nodiscard]] std::size_t live_tracks() const noexcept { return live_.size(); }

 private:
  struct Slot;
  void predict(Slot& s, double dt) const noexcept;
  // learns_extent: d may lengthen the track's known extent (not a union made inside that body).
  void correct(Slot& s, const Detection& d, std::int64_t stamp_ns, bool learns_extent,
               const Eigen::Matrix2d* spread = nullptr, bool single = false) noexcept;
  bool spawn(const Detection& d, std::int64_t stamp_ns) noexcept;  // false: not spawned (counted)
  void absorb_fragments(std::span<const Detection> detections) noexcept;
  // Whether fragment f lies wholly inside the known body of track slot s (absorb_known_margin_m).
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
  void merge_overlapping(std::int64_t stamp_ns) noexcept;
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
