// The tracker's scan loop (docs/tracking.md): predict, gate and assign (association.cpp), join
// fragments (fragments.cpp), correct (kalman.cpp), prune, spawn, merge overlaps, report. Known
// bodies and end-on faces are in body.cpp.
#include "perception/tracking/tracker.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "perception/tracking/shapes.hpp"
#include "perception/tracking/slot.hpp"

namespace stac::tracking {
namespace {

constexpr std::size_t kMaxTrackDetectionPairs = std::size_t{1} << 22;

void check(bool ok, const char* what) {
  if (!ok) throw std::invalid_argument(std::string("tracking config: ") + what);
}

// Every check of the configuration, before the constructor allocates anything (an oversized
// capacity is an error, never an attempt to allocate it).
const TrackerConfig& validated(const TrackerConfig& c) {
  check(c.max_tracks >= 1 && c.max_tracks <= 100000, "max_tracks must be in 1..100000");
  check(c.max_detections >= 1 && c.max_detections <= 100000, "max_detections must be in 1..100000");
  check(c.max_tracks * c.max_detections <= kMaxTrackDetectionPairs,
        "max_tracks x max_detections must be at most 4194304 (the assignment's cost matrix)");
  check(c.kalman.accel_std_mps2 > 0 && c.kalman.z_velocity_std_mps > 0,
        "process noise must be > 0");
  check(c.kalman.measurement_std_m > 0 && c.kalman.measurement_z_std_m > 0,
        "measurement noise must be > 0");
  check(c.kalman.initial_velocity_std_mps > 0, "initial_velocity_std_mps must be > 0");
  check(c.gate.mahalanobis_sq > 0 && c.gate.distance_m > 0, "gates must be > 0");
  check(c.life.confirm_hits >= 1, "confirm_hits must be >= 1");
  check(c.life.max_position_std_m > c.kalman.measurement_std_m,
        "max_position_std_m must exceed measurement_std_m");
  check(c.box_smoothing > 0 && c.box_smoothing <= 1, "box_smoothing must be in (0, 1]");
  check(c.fragments.gap_m >= 0 && c.fragments.gap_m <= 10, "absorb_gap_m must be in [0, 10]");
  check(c.object.max_length_m > 0 && c.object.max_width_m > 0 &&
            c.object.max_width_m <= c.object.max_length_m,
        "absorb_max_length_m >= absorb_max_width_m > 0 required");
  check(c.object.tall_height_m >= 0 && c.object.tall_length_m >= 0,
        "absorb_tall_height_m and absorb_tall_length_m must be >= 0");
  check(c.end_on.min_range_m >= 0, "end_on_min_range_m must be >= 0");
  check(c.end_on.length_m >= 0 && c.end_on.min_width_m <= c.end_on.max_width_m &&
            c.end_on.max_depth_m >= 0 && c.end_on.min_height_m >= 0,
        "end_on_length_m >= 0, end_on_min_width_m <= end_on_max_width_m, depth and height >= 0 "
        "required");
  check(c.person.gap_m >= 0, "absorb_narrow_gap_m must be >= 0");
  check(c.body.memory_length_m >= 0 && c.body.memory_length_m <= 100,
        "extent_memory_length_m must be in [0, 100] (0: off)");
  check(c.person.wide_m >= 0 && c.person.wide_min_height_m >= 0,
        "absorb_keep_wide_m and absorb_keep_wide_height_m must be >= 0");
  check(c.person.strip_length_m >= 0 && c.person.strip_width_m >= 0,
        "absorb_strip_length_m and absorb_strip_width_m must be >= 0");
  check(c.fragments.overlap_margin_m <= 5, "overlap_margin_m must be at most 5 (< 0: off)");
  check(c.fragments.known_margin_m <= 5, "absorb_known_margin_m must be at most 5 (< 0: off)");
  check(c.fragments.velocity_mps >= 0 && c.person.max_length_m >= 0 && c.person.max_width_m >= 0 &&
            c.person.min_height_m >= 0,
        "absorb_velocity_mps and absorb_keep_length_m, _width_m, _height_m must be >= 0");
  return c;
}

}  // namespace

Tracker::Tracker(const TrackerConfig& c)
    : config_(validated(c)),
      live_(c.max_tracks),
      free_(c.max_tracks),
      solver_(c.max_tracks, c.max_detections) {
  slots_.resize(c.max_tracks);
  for (std::size_t i = c.max_tracks; i-- > 0;) (void)free_.push_back(static_cast<std::uint32_t>(i));
  cost_.assign(c.max_tracks * c.max_detections, 0.0);
  pair_cost_.assign(c.max_tracks * c.max_detections, -1.0f);
  row_to_col_.assign(std::max(c.max_tracks, c.max_detections), -1);
  det_match_.assign(c.max_detections, -1);
  merged_.assign(c.max_detections, Detection{});
  host_.assign(c.max_detections, 0);
  merged_track_.assign(c.max_tracks, 0);
  rows_.assign(c.max_tracks, 0);
  cols_.assign(c.max_detections, 0);
  col_of_det_.assign(c.max_detections, -1);
  positions_.assign(c.max_detections, Eigen::Vector2d::Zero());
  track_xy_.assign(c.max_tracks, Eigen::Vector2d::Zero());
  order_.assign(c.max_tracks, 0);
  rank_.assign(c.max_tracks, 0);
  candidate_.assign(c.max_tracks, 0);
  parent_.assign(c.max_tracks + c.max_detections, 0);
  component_.assign(c.max_tracks + c.max_detections, 0);
  component_start_.assign(2 * (c.max_tracks + 1), 0);
  component_members_.assign(c.max_tracks + c.max_detections, 0);
}

Tracker::~Tracker() = default;

void Tracker::correct(Slot& s, const Detection& d, std::int64_t stamp_ns, bool learns_extent,
                      const Eigen::Matrix2d* spread, bool single) noexcept {
  const Eigen::Vector2f xy = d.position(config_.position_from_box);
  s.kf.correct(KalmanFilter::Meas(xy.x(), xy.y(), d.centroid.z()), config_.kalman, spread);

  Track& t = s.track;
  const double w = config_.box_smoothing;
  t.length = static_cast<float>(t.length + w * (d.length - t.length));
  t.width = static_cast<float>(t.width + w * (d.width - t.width));
  t.height = static_cast<float>(t.height + w * (d.height - t.height));
  t.yaw = static_cast<float>(shapes::wrap_pi(t.yaw + w * shapes::box_angle_diff(d.yaw, t.yaw)));
  t.points = d.points;
  t.segment = static_cast<std::int32_t>(d.segment);
  ++t.hits;
  t.misses = 0;
  if (t.state == TrackState::kCoasting || t.hits >= config_.life.confirm_hits ||
      (config_.life.confirm_large_points > 0 && d.points >= config_.life.confirm_large_points &&
       t.hits >= config_.life.confirm_large_hits))
    t.state = TrackState::kConfirmed;
  t.features.add_segment(Eigen::Vector3f(xy.x(), xy.y(), d.centroid.z()), stamp_ns,
                         config_.min_heading_speed_mps);
  if (const float known = shapes::tall_length(config_, d); learns_extent && known > 0) {
    s.known_length = std::max(s.known_length, known);
    s.known_width = std::max(s.known_width, d.width);
    if (single && !d.end_on) {
      if (known >= s.single_first) {
        s.known_single = s.single_first, s.single_first = known;
      } else {
        s.known_single = std::max(s.known_single, known);
      }
    }
    if (shapes::knows_extent(config_, known) && !d.end_on) s.known_yaw = d.yaw;
  }
}

bool Tracker::spawn(const Detection& d, std::int64_t stamp_ns) noexcept {
  const Eigen::Vector2f xy = d.position(config_.position_from_box);
  // Never gated either: NaN fails every comparison.
  if (!d.centroid.allFinite() || !xy.allFinite()) {
    ++counters_.invalid_detections;
    return false;
  }
  if (free_.empty()) {
    ++counters_.pool_overflow;
    return false;
  }
  const std::uint32_t index = free_.back();
  free_.pop_back();
  (void)live_.push_back(index);
  Slot& s = slots_[index];
  s.kf.start(KalmanFilter::Meas(xy.x(), xy.y(), d.centroid.z()), config_.kalman);
  s.track = Track{};
  Track& t = s.track;
  t.id = next_id_++;
  t.slot = index;
  t.state = config_.life.confirm_hits <= 1 ? TrackState::kConfirmed : TrackState::kTentative;
  t.length = std::isfinite(d.length) ? d.length : 0.0f;
  t.width = std::isfinite(d.width) ? d.width : 0.0f;
  t.height = std::isfinite(d.height) ? d.height : 0.0f;
  t.yaw = std::isfinite(d.yaw) ? d.yaw : 0.0f;
  t.points = d.points;
  t.segment = static_cast<std::int32_t>(d.segment);
  t.hits = 1;
  s.known_length = shapes::tall_length(config_, d);
  s.known_width = s.known_length > 0 ? d.width : 0.0f;
  s.single_first = d.end_on ? 0.0f : s.known_length;
  s.known_single = 0;
  s.known_yaw = t.yaw;
  t.features.add_segment(Eigen::Vector3f(xy.x(), xy.y(), d.centroid.z()), stamp_ns,
                         config_.min_heading_speed_mps);
  ++counters_.spawned;
  return true;
}

void Tracker::update(std::int64_t stamp_ns, std::span<const Detection> detections,
                     TrackerOutput& out, const Eigen::Vector2f* sensor_xy) noexcept {
  ++counters_.scans;
  have_sensor_ = sensor_xy != nullptr && sensor_xy->allFinite();
  if (have_sensor_) sensor_xy_ = *sensor_xy;
  if (detections.size() > config_.max_detections) {
    counters_.dropped_detections += detections.size() - config_.max_detections;
    detections = detections.first(config_.max_detections);
  }
  scan_ = detections;
  predict_all(stamp_ns);
  // Global assignment over the gated sub-matrix, per connected component of the allowed pairs.
  const Gated gated = gate(detections);
  if (gated.rows > 0) assign(detections.size(), gated.rows, gated.cols);
  absorb_fragments(detections);
  correct_matched(stamp_ns, detections.size());
  prune();
  spawn_unmatched(stamp_ns, detections);
  merge_overlapping(stamp_ns);
  report(stamp_ns, out);
}

void Tracker::predict_all(std::int64_t stamp_ns) noexcept {
  double dt = 0;
  if (have_stamp_) {
    dt = static_cast<double>(stamp_ns - last_stamp_ns_) * 1e-9;
    if (dt <= 0) ++counters_.stamp_regressions;
  }
  if (!have_stamp_ || dt > 0) last_stamp_ns_ = stamp_ns;
  have_stamp_ = true;
  for (const std::uint32_t i : live_) {
    slots_[i].kf.predict(dt, config_.kalman);
    slots_[i].measured = -1;
    Track& t = slots_[i].track;
    t.segment = -1;
    if (dt > 0) ++t.age;
  }
}

void Tracker::correct_matched(std::int64_t stamp_ns, std::size_t nd) noexcept {
  for (std::size_t di = 0; di < nd; ++di) {
    if (det_match_[di] < 0) continue;
    Slot& slot = slots_[live_[static_cast<std::size_t>(det_match_[di])]];
    Detection& m = merged_[di];  // an end-on face of a known body: the body already
    Eigen::Matrix2d spread;
    float gap = 0;
    Eigen::Vector2f centre = Eigen::Vector2f::Zero();
    const bool is_piece = piece(slot, m, di, spread, gap, centre);
    if (is_piece) m.box_center = centre;
    // A body's union never lengthens it; a piece of it measures the body's centre loosely.
    correct(slot, m, stamp_ns, host_[di] != kBodyHost, is_piece ? &spread : nullptr,
            host_[di] == 0);
    slot.measured = static_cast<std::int32_t>(di);
  }
}

void Tracker::prune() noexcept {
  // Misses and uncertainty, compacting the live list in place, order kept. Only the steps after
  // this one change the live list: its indices are still those of merged_track_.
  const std::size_t nt = live_.size();
  std::size_t kept = 0;
  for (std::size_t ti = 0; ti < nt; ++ti) {
    const std::uint32_t index = live_[ti];
    Slot& s = slots_[index];
    Track& t = s.track;
    bool remove = merged_track_[ti] != 0;  // its fragment joined an older track's measurement
    if (!remove && t.segment < 0) {
      ++t.misses;
      if (t.state == TrackState::kTentative) {
        if (t.misses > config_.life.tentative_max_misses) {
          remove = true;
          ++counters_.deleted_tentative;
        }
      } else {
        t.state = TrackState::kCoasting;
        if (s.kf.position_std() > config_.life.max_position_std_m) {
          remove = true;
          ++counters_.deleted_uncertain;
        } else if (t.misses > config_.life.max_coast_scans) {
          remove = true;
          ++counters_.deleted_coasting;
        }
      }
    }
    if (remove) {
      (void)free_.push_back(index);
    } else {
      live_[kept++] = index;
    }
  }
  (void)live_.resize(kept);
}

void Tracker::spawn_unmatched(std::int64_t stamp_ns,
                              std::span<const Detection> detections) noexcept {
  // Unmatched detections (not absorbed) spawn tentative tracks.
  for (std::size_t di = 0; di < detections.size(); ++di) {
    if (det_match_[di] == kUnmatched && spawn(detections[di], stamp_ns)) {
      slots_[live_.back()].measured = static_cast<std::int32_t>(di);
    }
  }
}

void Tracker::report(std::int64_t stamp_ns, TrackerOutput& out) noexcept {
  out.stamp_ns = stamp_ns;
  out.tracks.clear();
  for (const std::uint32_t i : live_) {
    Slot& s = slots_[i];
    Track& t = s.track;
    t.position = s.kf.x.head<3>().cast<float>();
    t.velocity = s.kf.x.tail<2>().cast<float>();
    t.position_std_m = static_cast<float>(s.kf.position_std());
    if (!out.tracks.push_back(t)) break;
  }
  out.counters = counters_;
}

}  // namespace stac::tracking
