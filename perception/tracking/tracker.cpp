#include "perception/tracking/tracker.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace stac::tracking {
namespace {

using State = Eigen::Matrix<double, 5, 1>;  // px, py, pz, vx, vy
using Cov = Eigen::Matrix<double, 5, 5>;
using Meas = Eigen::Matrix<double, 3, 1>;  // px, py, pz
using MeasCov = Eigen::Matrix<double, 3, 3>;
using Gain = Eigen::Matrix<double, 5, 3>;

constexpr double kForbidden = 1e9;       // cost of a pair outside the gate (dropped after solving)
constexpr std::int32_t kUnmatched = -1;  // det_match_: no track (spawns one)
constexpr std::int32_t kAbsorbed = -2;   // det_match_: joined a matched track's measurement
// host_ per detection: 0 none joined it; kHost a fragment did; kBodyHost one inside a known body
// did (TrackerConfig::absorb_known_margin_m), so its measurement never lengthens that extent.
constexpr std::uint8_t kHost = 1, kBodyHost = 2;

// Angle difference wrapped to [-pi/2, pi/2): box headings are defined modulo pi.
double box_angle_diff(double a, double b) {
  double d = std::fmod(a - b, std::numbers::pi);
  if (d >= std::numbers::pi / 2) d -= std::numbers::pi;
  if (d < -std::numbers::pi / 2) d += std::numbers::pi;
  return d;
}

double wrap_pi(double a) {
  a = std::fmod(a + std::numbers::pi, 2 * std::numbers::pi);
  if (a < 0) a += 2 * std::numbers::pi;
  return a - std::numbers::pi;
}

double position_std(const Cov& p) {
  // Largest eigenvalue of the symmetric 2x2 x,y block, in closed form.
  const double a = p(0, 0), b = p(0, 1), d = p(1, 1);
  const double mean = 0.5 * (a + d);
  const double spread = std::sqrt(0.25 * (a - d) * (a - d) + b * b);
  return std::sqrt(std::max(0.0, mean + spread));
}

// A box's extent along the axes u = (cos h, sin h), v = (-sin h, cos h) of heading h.
struct Extent {
  float u0, u1, v0, v1;
};

// The smallest extent holding both.
Extent hull(const Extent& a, const Extent& b) {
  return {std::min(a.u0, b.u0), std::max(a.u1, b.u1), std::min(a.v0, b.v0), std::max(a.v1, b.v1)};
}

// The extent of the box (box_centre, length x width at yaw) about `centre` along heading h.
Extent extent_in(const Eigen::Vector2f& box_centre, float length, float width, float yaw,
                 const Eigen::Vector2f& centre, float h) {
  const float ch = std::cos(h), sh = std::sin(h);
  const float cy = std::cos(yaw), sy = std::sin(yaw);
  const Eigen::Vector2f c = box_centre - centre;
  const float uc = ch * c.x() + sh * c.y(), vc = -sh * c.x() + ch * c.y();
  // Half-extents of the rotated box along u and v.
  const float a = 0.5f * length, b = 0.5f * width;
  const float du = std::abs(a * (ch * cy + sh * sy)) + std::abs(b * (-ch * sy + sh * cy));
  const float dv = std::abs(a * (-sh * cy + ch * sy)) + std::abs(b * (sh * sy + ch * cy));
  return {uc - du, uc + du, vc - dv, vc + dv};
}

Extent extent_in(const Detection& d, const Eigen::Vector2f& centre, float h) {
  return extent_in(d.position(true), d.length, d.width, d.yaw, centre, h);
}

// Whether a box of this height is a tall vehicle's (a truck's: absorb_tall_height_m).
bool tall(const TrackerConfig& c, float height) {
  return c.absorb_tall_height_m > 0 && height >= c.absorb_tall_height_m;
}

// The longest box one fragmented object may span: absorb_max_length_m, or absorb_tall_length_m
// (if longer) for a tall one.
double longest_object(const TrackerConfig& c, bool tall_object) {
  return tall_object ? std::max(c.absorb_max_length_m, c.absorb_tall_length_m)
                     : c.absorb_max_length_m;
}

// A box that fits what one fragmented object may span (longest_object x absorb_max_width_m).
bool fits_one_object(const TrackerConfig& c, float length, float width, bool tall_object) {
  return std::max(length, width) <= longest_object(c, tall_object) &&
         std::min(length, width) <= c.absorb_max_width_m;
}

// Which of two tracks is older: more hits, then the lower id (the merges keep the older).
bool older(const Track& a, const Track& b) {
  return a.hits > b.hits || (a.hits == b.hits && a.id < b.id);
}

// People and bicyclists: never joined to other objects (TrackerConfig::absorb_keep_*).
bool narrow_and_tall(const TrackerConfig& c, float length, float width, float height) {
  const float wide = std::min(length, width), longest = std::max(length, width);
  if (c.absorb_strip_width_m > 0 && wide <= c.absorb_strip_width_m &&
      longest >= c.absorb_strip_length_m) {
    return false;  // a flat strip: a car's side or a wall seen edge-on, not a person
  }
  return longest <= c.absorb_keep_length_m &&
         ((wide <= c.absorb_keep_width_m && height >= c.absorb_keep_height_m) ||
          (wide <= c.absorb_keep_wide_m && height >= c.absorb_keep_wide_height_m));
}

// What a measurement tells a track of its known extent (extent_memory_length_m): its length
// when it is a tall box that fits one object, else 0.
float tall_length(const TrackerConfig& c, const Detection& d) {
  return tall(c, d.height) && fits_one_object(c, d.length, d.width, true) ? d.length : 0.0f;
}

// Whether a track that remembers `known` m measures end-on faces with it (memory on and long
// enough).
bool knows_extent(const TrackerConfig& c, float known) {
  return c.extent_memory_length_m > 0 && known >= c.extent_memory_length_m;
}

// Known extent (TrackerConfig::extent_memory_length_m): the centre of the body, `known` m long
// along heading `body_yaw` (the track's known_yaw), whose face end-on detection d is: its near
// end (the face) kept, the body extending from it away from the sensor. complete_end_on turned
// d's box along the sensor's ray, which for a vehicle not straight ahead is not its heading.
// False (centre unchanged) when memory is off or not yet that long, d is not end-on or longer,
// or d's box does not lie along the body's heading (within 30 degrees).
bool anchored_centre(const TrackerConfig& c, float known, float body_yaw, const Detection& d,
                     Eigen::Vector2f& centre) {
  if (!knows_extent(c, known) || !c.position_from_box || !d.end_on || !(d.length < known) ||
      !d.box_center.allFinite() ||
      !(std::abs(box_angle_diff(d.yaw, body_yaw)) <= std::numbers::pi / 6)) {
    return false;
  }
  // complete_end_on's box points away from the sensor along its yaw: its near end is the face.
  const Eigen::Vector2f ray(std::cos(d.yaw), std::sin(d.yaw));
  Eigen::Vector2f heading(std::cos(body_yaw), std::sin(body_yaw));
  if (heading.dot(ray) < 0) heading = -heading;
  centre = d.box_center - (0.5f * d.length) * ray + (0.5f * known) * heading;
  return true;
}

// Known extent (TrackerConfig::body_gating): tall detection d as a piece of the known body
// (`known` m long, `known_width` m wide, along the track's heading). Where in the body the piece
// lies is unknown, so it measures the body's centre at its own box centre, with the variance of a
// position uniform over the slack added: (known - the piece's extent along the heading)^2 / 12
// along, (known_width - its extent across)^2 / 12 across (m^2, in `spread` in x,y). `gap` is the
// distance from the prediction to the nearest centre at which the body covers the piece (the
// distance gate's). Along the heading, when `occluded(u0, u1, vc)` (Tracker::hidden_end) says
// that exactly one end of the piece is hidden behind a nearer object, the other end, in view,
// is the body's: the centre lies `known_single` / 2 from it (the length of at least two
// one-segment views, so that one view of two vehicles as one segment does not set it), and no
// spread is added along. `centre`: the body's centre measured. False when this is
// off, memory is off or not yet that long, d is end-on (anchored_centre), lower than
// absorb_tall_height_m, a person, not shorter than the body, longer than it along the heading,
// or not along the track's box (within 30 degrees).
template <class Occluded>
bool piece_of_body(const TrackerConfig& c, float known, float known_single, float known_width,
                   float track_yaw, const Eigen::Vector2f& predicted, const Detection& d,
                   Eigen::Matrix2d& spread, float& gap, Eigen::Vector2f& centre,
                   Occluded&& occluded) {
  if (!c.body_gating || !knows_extent(c, known) || !c.position_from_box || d.end_on ||
      !(d.length < known) || !d.box_center.allFinite() || !tall(c, d.height) ||
      narrow_and_tall(c, d.length, d.width, d.height) ||
      !(std::abs(box_angle_diff(d.yaw, track_yaw)) <= std::numbers::pi / 6)) {
    return false;
  }
  const Extent e = extent_in(d, predicted, track_yaw);
  const float slack_u = known - (e.u1 - e.u0);
  if (!(slack_u >= 0)) return false;
  const float slack_v = std::max(0.0f, known_width - (e.v1 - e.v0));
  float uc = 0.5f * (e.u0 + e.u1);
  const float vc = 0.5f * (e.v0 + e.v1);
  bool anchored = false;
  double var_u = slack_u * slack_u / 12.0;
  if (knows_extent(c, known_single) && known_single > e.u1 - e.u0) {
    const int hidden = occluded(e.u0, e.u1, vc);
    if (hidden == 1) uc = e.u1 - 0.5f * known_single, anchored = true;  // the low end hidden
    if (hidden == 2) uc = e.u0 + 0.5f * known_single, anchored = true;  // the high end hidden
    if (anchored) var_u = 0;
  }
  gap = std::hypot(anchored ? std::abs(uc) : std::max(0.0f, std::abs(uc) - 0.5f * slack_u),
                   std::max(0.0f, std::abs(vc) - 0.5f * slack_v));
  const double cy = std::cos(track_yaw), sy = std::sin(track_yaw);
  Eigen::Matrix2d rot;
  rot << cy, -sy, sy, cy;
  const Eigen::Vector2d var(var_u, slack_v * slack_v / 12.0);
  spread = rot * var.asDiagonal() * rot.transpose();
  centre = predicted + Eigen::Vector2f(static_cast<float>(cy * uc - sy * vc),
                                       static_cast<float>(sy * uc + cy * vc));
  return true;
}

// Whether the segment from `from` to `to` passes through the box (centre, length x width at
// yaw) at most `before` m from `from`.
bool ray_hits_box(const Eigen::Vector2f& from, const Eigen::Vector2f& to,
                  const Eigen::Vector2f& centre, float length, float width, float yaw,
                  float before) {
  const float cy = std::cos(yaw), sy = std::sin(yaw);
  const Eigen::Vector2f a = from - centre, b = to - centre;
  const Eigen::Vector2f p(cy * a.x() + sy * a.y(), -sy * a.x() + cy * a.y());
  const Eigen::Vector2f q(cy * b.x() + sy * b.y(), -sy * b.x() + cy * b.y());
  const Eigen::Vector2f dir = q - p;
  const float hl = 0.5f * length, hw = 0.5f * width;
  float t0 = 0, t1 = 1;
  for (int axis = 0; axis < 2; ++axis) {
    const float lo = axis == 0 ? -hl : -hw, hi = axis == 0 ? hl : hw;
    if (std::abs(dir[axis]) < 1e-9f) {
      if (p[axis] < lo || p[axis] > hi) return false;
      continue;
    }
    float ta = (lo - p[axis]) / dir[axis], tb = (hi - p[axis]) / dir[axis];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta), t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  return t0 * dir.norm() <= before;
}

void check(bool ok, const char* what) {
  if (!ok) throw std::invalid_argument(std::string("tracking config: ") + what);
}

}  // namespace

const char* state_name(TrackState s) noexcept {
  switch (s) {
    case TrackState::kTentative:
      return "tentative";
    case TrackState::kConfirmed:
      return "confirmed";
    case TrackState::kCoasting:
      return "coasting";
  }
  return "unknown";
}

bool complete_end_on(const TrackerConfig& c, const Eigen::Vector2f& sensor_xy,
                     Detection& d) noexcept {
  if (c.end_on_length_m <= 0 || !d.box_center.allFinite()) return false;
  const Eigen::Vector2f ray = d.box_center - sensor_xy;
  const float range = ray.norm();
  if (!(range > 1e-3f) || range < c.end_on_min_range_m) return false;
  const Eigen::Vector2f r = ray / range;
  // The long side must lie across the ray (within 30 degrees of perpendicular).
  const float along = std::abs(r.x() * std::cos(d.yaw) + r.y() * std::sin(d.yaw));
  if (along > 0.5f || d.length < c.end_on_min_width_m || d.length > c.end_on_max_width_m ||
      d.width > c.end_on_max_depth_m || d.height < c.end_on_min_height_m) {
    return false;
  }
  const auto length = static_cast<float>(c.end_on_length_m);
  if (length <= d.width) return false;
  d.box_center += r * (0.5f * (length - d.width));
  d.width = d.length;
  d.length = length;
  d.yaw = std::atan2(r.y(), r.x());
  d.end_on = true;
  return true;
}

void HolisticFeatures::add_segment(const Eigen::Vector3f& centroid, std::int64_t stamp_ns,
                                   double min_heading_speed_mps) noexcept {
  ++segments_;
  centroids_[static_cast<std::size_t>(head_)] = centroid;
  stamps_[static_cast<std::size_t>(head_)] = stamp_ns;
  head_ = (head_ + 1) % kWindow;
  filled_ = std::min(filled_ + 1, kWindow);
  if (filled_ < 2) return;
  const auto newest = static_cast<std::size_t>((head_ + kWindow - 1) % kWindow);
  const auto oldest = static_cast<std::size_t>((head_ + kWindow - filled_) % kWindow);
  const double span_s = static_cast<double>(stamps_[newest] - stamps_[oldest]) * 1e-9;
  if (!(span_s > 0)) return;
  const Eigen::Vector2f v =
      ((centroids_[newest] - centroids_[oldest]).head<2>() / static_cast<float>(span_s)).eval();
  const float speed = v.norm();
  max_speed_ = std::max(max_speed_, speed);
  speed_sum_ += speed;
  ++speed_count_;
  if (have_velocity_) {
    const double dt = static_cast<double>(stamp_ns - velocity_stamp_) * 1e-9;
    if (dt > 0) {
      const auto accel = static_cast<float>((v - velocity_).norm() / dt);
      max_accel_ = std::max(max_accel_, accel);
      accel_sum_ += accel;
      ++accel_count_;
      if (speed >= min_heading_speed_mps && velocity_.norm() >= min_heading_speed_mps) {
        const double turn =
            wrap_pi(std::atan2(v.y(), v.x()) - std::atan2(velocity_.y(), velocity_.x()));
        max_angular_ = std::max(max_angular_, static_cast<float>(std::abs(turn) / dt));
      }
    }
  }
  velocity_ = v;
  velocity_stamp_ = stamp_ns;
  have_velocity_ = true;
}

float HolisticFeatures::mean_speed_mps() const noexcept {
  return speed_count_ == 0 ? 0.0f : static_cast<float>(speed_sum_ / speed_count_);
}

float HolisticFeatures::mean_accel_mps2() const noexcept {
  return accel_count_ == 0 ? 0.0f : static_cast<float>(accel_sum_ / accel_count_);
}

struct Tracker::Slot {
  Track track;
  State x = State::Zero();
  Cov p = Cov::Identity();
  std::int32_t measured = -1;  // index in merged_ of the measurement of this scan, -1: none
  float known_length = 0;      // longest tall measurement so far (extent_memory_length_m), m
  float known_width = 0;       // widest tall measurement so far (the body's width), m
  // The two longest tall measurements of one segment (no union, not end-on), m: the second is
  // the body's length for a piece anchored at its visible end (one view of two vehicles as one
  // segment does not make it).
  float single_first = 0, known_single = 0;
  // Heading of the last tall measurement at least extent_memory_length_m long that was not an
  // end-on face (whose yaw is the sensor's ray): the body's, for its faces and its joins (rad).
  float known_yaw = 0;
};

namespace {

constexpr std::size_t kMaxTrackDetectionPairs = std::size_t{1} << 22;

// Every check of the configuration, before the constructor allocates anything (an oversized
// capacity is an error, never an attempt to allocate it).
const TrackerConfig& validated(const TrackerConfig& c) {
  check(c.max_tracks >= 1 && c.max_tracks <= 100000, "max_tracks must be in 1..100000");
  check(c.max_detections >= 1 && c.max_detections <= 100000, "max_detections must be in 1..100000");
  check(c.max_tracks * c.max_detections <= kMaxTrackDetectionPairs,
        "max_tracks x max_detections must be at most 4194304 (the assignment's cost matrix)");
  check(c.accel_std_mps2 > 0 && c.z_velocity_std_mps > 0, "process noise must be > 0");
  check(c.measurement_std_m > 0 && c.measurement_z_std_m > 0, "measurement noise must be > 0");
  check(c.initial_velocity_std_mps > 0, "initial_velocity_std_mps must be > 0");
  check(c.gate_mahalanobis_sq > 0 && c.gate_distance_m > 0, "gates must be > 0");
  check(c.confirm_hits >= 1, "confirm_hits must be >= 1");
  check(c.max_position_std_m > c.measurement_std_m,
        "max_position_std_m must exceed measurement_std_m");
  check(c.box_smoothing > 0 && c.box_smoothing <= 1, "box_smoothing must be in (0, 1]");
  check(c.absorb_gap_m >= 0 && c.absorb_gap_m <= 10, "absorb_gap_m must be in [0, 10]");
  check(c.absorb_max_length_m > 0 && c.absorb_max_width_m > 0 &&
            c.absorb_max_width_m <= c.absorb_max_length_m,
        "absorb_max_length_m >= absorb_max_width_m > 0 required");
  check(c.absorb_tall_height_m >= 0 && c.absorb_tall_length_m >= 0,
        "absorb_tall_height_m and absorb_tall_length_m must be >= 0");
  check(c.end_on_min_range_m >= 0, "end_on_min_range_m must be >= 0");
  check(c.end_on_length_m >= 0 && c.end_on_min_width_m <= c.end_on_max_width_m &&
            c.end_on_max_depth_m >= 0 && c.end_on_min_height_m >= 0,
        "end_on_length_m >= 0, end_on_min_width_m <= end_on_max_width_m, depth and height >= 0 "
        "required");
  check(c.absorb_narrow_gap_m >= 0, "absorb_narrow_gap_m must be >= 0");
  check(c.extent_memory_length_m >= 0 && c.extent_memory_length_m <= 100,
        "extent_memory_length_m must be in [0, 100] (0: off)");
  check(c.absorb_keep_wide_m >= 0 && c.absorb_keep_wide_height_m >= 0,
        "absorb_keep_wide_m and absorb_keep_wide_height_m must be >= 0");
  check(c.absorb_strip_length_m >= 0 && c.absorb_strip_width_m >= 0,
        "absorb_strip_length_m and absorb_strip_width_m must be >= 0");
  check(c.overlap_margin_m <= 5, "overlap_margin_m must be at most 5 (< 0: off)");
  check(c.absorb_known_margin_m <= 5, "absorb_known_margin_m must be at most 5 (< 0: off)");
  check(c.absorb_velocity_mps >= 0 && c.absorb_keep_length_m >= 0 && c.absorb_keep_width_m >= 0 &&
            c.absorb_keep_height_m >= 0,
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

void Tracker::predict(Slot& s, double dt) const noexcept {
  if (dt <= 0) return;
  Cov f = Cov::Identity();
  f(0, 3) = dt;
  f(1, 4) = dt;
  s.x = f * s.x;
  const double q = config_.accel_std_mps2 * config_.accel_std_mps2;
  Cov qm = Cov::Zero();
  for (int axis = 0; axis < 2; ++axis) {  // white-noise acceleration, per axis
    qm(axis, axis) = q * dt * dt * dt * dt / 4;
    qm(axis, axis + 3) = qm(axis + 3, axis) = q * dt * dt * dt / 2;
    qm(axis + 3, axis + 3) = q * dt * dt;
  }
  qm(2, 2) = config_.z_velocity_std_mps * config_.z_velocity_std_mps * dt * dt;
  s.p = f * s.p * f.transpose() + qm;
}

void Tracker::correct(Slot& s, const Detection& d, std::int64_t stamp_ns, bool learns_extent,
                      const Eigen::Matrix2d* spread, bool single) noexcept {
  const double r = config_.measurement_std_m * config_.measurement_std_m;
  const double rz = config_.measurement_z_std_m * config_.measurement_z_std_m;
  MeasCov rm = MeasCov::Zero();
  rm.diagonal() = Meas(r, r, rz);
  if (spread != nullptr) rm.topLeftCorner<2, 2>() += *spread;  // a piece of a known body
  MeasCov sm = s.p.topLeftCorner<3, 3>() + rm;
  const Gain k = s.p.leftCols<3>() * sm.inverse();
  const Eigen::Vector2f xy = d.position(config_.position_from_box);
  const Meas innovation = Meas(xy.x(), xy.y(), d.centroid.z()) - s.x.head<3>();
  s.x += k * innovation;
  Cov ikh = Cov::Identity();
  ikh.leftCols<3>() -= k;
  s.p = ikh * s.p * ikh.transpose() + k * rm * k.transpose();  // Joseph form: stays symmetric PSD

  Track& t = s.track;
  const double w = config_.box_smoothing;
  t.length = static_cast<float>(t.length + w * (d.length - t.length));
  t.width = static_cast<float>(t.width + w * (d.width - t.width));
  t.height = static_cast<float>(t.height + w * (d.height - t.height));
  t.yaw = static_cast<float>(wrap_pi(t.yaw + w * box_angle_diff(d.yaw, t.yaw)));
  t.points = d.points;
  t.segment = static_cast<std::int32_t>(d.segment);
  ++t.hits;
  t.misses = 0;
  if (t.state == TrackState::kCoasting || t.hits >= config_.confirm_hits ||
      (config_.confirm_large_points > 0 && d.points >= config_.confirm_large_points &&
       t.hits >= config_.confirm_large_hits))
    t.state = TrackState::kConfirmed;
  t.features.add_segment(Eigen::Vector3f(xy.x(), xy.y(), d.centroid.z()), stamp_ns,
                         config_.min_heading_speed_mps);
  if (const float known = tall_length(config_, d); learns_extent && known > 0) {
    s.known_length = std::max(s.known_length, known);
    s.known_width = std::max(s.known_width, d.width);
    if (single && !d.end_on) {
      if (known >= s.single_first) {
        s.known_single = s.single_first, s.single_first = known;
      } else {
        s.known_single = std::max(s.known_single, known);
      }
    }
    if (knows_extent(config_, known) && !d.end_on) s.known_yaw = d.yaw;
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
  s.x = State::Zero();
  s.x.head<3>() = Eigen::Vector3d(xy.x(), xy.y(), d.centroid.z());
  s.p = Cov::Zero();
  const double r = config_.measurement_std_m * config_.measurement_std_m;
  const double v = config_.initial_velocity_std_mps * config_.initial_velocity_std_mps;
  s.p.diagonal() << r, r, config_.measurement_z_std_m * config_.measurement_z_std_m, v, v;
  s.track = Track{};
  Track& t = s.track;
  t.id = next_id_++;
  t.slot = index;
  t.state = config_.confirm_hits <= 1 ? TrackState::kConfirmed : TrackState::kTentative;
  t.length = std::isfinite(d.length) ? d.length : 0.0f;
  t.width = std::isfinite(d.width) ? d.width : 0.0f;
  t.height = std::isfinite(d.height) ? d.height : 0.0f;
  t.yaw = std::isfinite(d.yaw) ? d.yaw : 0.0f;
  t.points = d.points;
  t.segment = static_cast<std::int32_t>(d.segment);
  t.hits = 1;
  s.known_length = tall_length(config_, d);
  s.known_width = s.known_length > 0 ? d.width : 0.0f;
  s.single_first = d.end_on ? 0.0f : s.known_length;
  s.known_single = 0;
  s.known_yaw = t.yaw;
  t.features.add_segment(Eigen::Vector3f(xy.x(), xy.y(), d.centroid.z()), stamp_ns,
                         config_.min_heading_speed_mps);
  ++counters_.spawned;
  return true;
}

int Tracker::hidden_end(const Slot& s, const Detection& d, float u0, float u1,
                        float vc) const noexcept {
  if (!have_sensor_) return 0;
  const Eigen::Vector2f predicted = s.x.head<2>().cast<float>();
  const float cy = std::cos(s.track.yaw), sy = std::sin(s.track.yaw);
  const Eigen::Vector2f h(cy, sy), v(-sy, cy);
  // An end is hidden when the line of sight to the point 0.3 m beyond it (along the heading)
  // passes through another detection's box at least 0.5 m nearer than that point: the body may
  // go on behind it. An end whose beyond is in view is a real end.
  const auto hidden = [&](float u, float beyond) {
    const Eigen::Vector2f end = predicted + h * (u + beyond) + v * vc;
    const Eigen::Vector2f sight = end - sensor_xy_;
    const float range = sight.norm();
    if (!(range > 0.5f)) return false;
    const Eigen::Vector2f along = sight / range;
    for (const Detection& o : scan_) {
      if (&o == &d || !o.box_center.allFinite()) continue;
      // Cheap test first: a box farther from the line of sight than its half diagonal is missed.
      const Eigen::Vector2f rel = o.position(true) - sensor_xy_;
      const float t = std::clamp(rel.dot(along), 0.0f, range);
      const float reach = 0.5f * std::hypot(o.length, o.width) + 1e-3f;
      if ((rel - t * along).squaredNorm() > reach * reach) continue;
      if (inside_known_body(s, o)) continue;  // a piece of the same body
      if (ray_hits_box(sensor_xy_, end, o.position(true), o.length, o.width, o.yaw, range - 0.5f))
        return true;
    }
    return false;
  };
  const bool lo = hidden(u0, -0.3f), hi = hidden(u1, 0.3f);
  return lo && !hi ? 1 : (hi && !lo ? 2 : 0);
}

bool Tracker::piece(const Slot& s, const Detection& m, std::size_t di, Eigen::Matrix2d& spread,
                    float& gap, Eigen::Vector2f& centre) const noexcept {
  return piece_of_body(
      config_, s.known_length, s.known_single, s.known_width, s.track.yaw,
      s.x.head<2>().cast<float>(), m, spread, gap, centre,
      [&](float u0, float u1, float vc) { return hidden_end(s, scan_[di], u0, u1, vc); });
}

bool Tracker::inside_known_body(const Slot& s, const Detection& f) const noexcept {
  if (config_.absorb_known_margin_m < 0 || !knows_extent(config_, s.known_length)) return false;
  const auto margin = static_cast<float>(config_.absorb_known_margin_m);
  const Extent e = extent_in(f, s.x.head<2>().cast<float>(), s.known_yaw);
  const float hl = 0.5f * s.known_length + margin, hw = 0.5f * s.track.width + margin;
  return e.u0 >= -hl && e.u1 <= hl && e.v0 >= -hw && e.v1 <= hw;
}

void Tracker::absorb_fragments(std::span<const Detection> detections) noexcept {
  const std::size_t nd = detections.size();
  for (std::size_t di = 0; di < nd; ++di) {
    merged_[di] = detections[di];
    host_[di] = 0;
    // An end-on face matched to a track of known extent is that body (its face kept) before
    // any fragment joins it.
    if (det_match_[di] >= 0) {
      const Slot& slot = slots_[live_[static_cast<std::size_t>(det_match_[di])]];
      Detection& m = merged_[di];
      Eigen::Vector2f centre = Eigen::Vector2f::Zero();
      if (anchored_centre(config_, slot.known_length, slot.known_yaw, m, centre)) {
        m.box_center = centre;
        m.length = slot.known_length;
        ++counters_.anchored_detections;
      }
    }
  }
  std::fill_n(merged_track_.begin(), live_.size(), std::uint8_t{0});
  if (config_.absorb_gap_m <= 0) return;
  const auto max_len =
      static_cast<float>(longest_object(config_, config_.absorb_tall_height_m > 0));
  const auto max_wid = static_cast<float>(config_.absorb_max_width_m);
  const auto max_gap = static_cast<float>(config_.absorb_gap_m);
  const float reach_sq = max_len * max_len + max_wid * max_wid;
  const auto person = [&](const Detection& d) {
    return narrow_and_tall(config_, d.length, d.width, d.height);
  };
  for (std::size_t fi = 0; fi < nd; ++fi) {
    const Detection& f = detections[fi];
    // A person-like piece joins only the known body of a truck it lies in (inside_known_body).
    const bool f_person = person(f);
    if (det_match_[fi] == kAbsorbed || host_[fi] != 0 || !f.centroid.allFinite() ||
        !f.position(true).allFinite()) {
      continue;
    }
    const Slot* own =
        det_match_[fi] >= 0 ? &slots_[live_[static_cast<std::size_t>(det_match_[fi])]] : nullptr;
    // A fragment whose own track is established joins only a person (its own legs), never a car.
    const bool established = own != nullptr && config_.absorb_established_hits > 0 &&
                             own->track.hits >= config_.absorb_established_hits;
    // The matched measurement nearest to the fragment (box gap) whose union with it still fits;
    // a matched fragment only joins an older track moving with it.
    std::size_t best = nd;
    float best_gap = max_gap;
    Extent best_union{};
    float best_heading = 0, best_area = 0;
    bool best_known = false;
    const Eigen::Vector2f fc = f.position(true);
    for (std::size_t hi = 0; hi < nd; ++hi) {
      if (hi == fi || det_match_[hi] < 0) continue;
      // A union that fits has a diagonal of at most reach: farther centres never fit (cheap test).
      if ((merged_[hi].position(true) - fc).squaredNorm() > reach_sq) continue;
      // A person or bicyclist takes only low pieces (legs, a wheel), whatever their tracks' ages,
      // and stays narrow.
      const bool narrow_host = person(merged_[hi]);
      const Slot& host = slots_[live_[static_cast<std::size_t>(det_match_[hi])]];
      const bool in_body = !narrow_host && inside_known_body(host, f);
      if (f_person && !in_body) continue;
      if (narrow_host && f.height >= config_.absorb_keep_height_m) continue;
      if (own != nullptr && !narrow_host) {
        if (established || !older(host.track, own->track)) continue;
        if (own->track.state != TrackState::kTentative &&
            (host.x.tail<2>() - own->x.tail<2>()).norm() > config_.absorb_velocity_mps) {
          continue;
        }
      }
      const Detection& h = merged_[hi];
      const Eigen::Vector2f centre = h.position(true);
      // Inside the body of a host track of known extent: joined in the body's heading (its
      // last whole view), the first such host taken.
      if (in_body) {
        const float heading = host.known_yaw;
        best = hi, best_heading = heading, best_known = true;
        best_union = hull(extent_in(h, centre, heading), extent_in(f, centre, heading));
        break;
      }
      // The union in the host's heading or the fragment's, whichever fits tighter (a piece's
      // principal axis may be diagonal to the car).
      for (const float heading : {h.yaw, f.yaw}) {
        const Extent a = extent_in(h, centre, heading), b = extent_in(f, centre, heading);
        const float gu = std::max(0.0f, std::max(a.u0, b.u0) - std::min(a.u1, b.u1));
        const float gv = std::max(0.0f, std::max(a.v0, b.v0) - std::min(a.v1, b.v1));
        const float gap = std::hypot(gu, gv);
        if (!(gap <= best_gap) || (narrow_host && gap > config_.absorb_narrow_gap_m)) continue;
        const Extent u = hull(a, b);
        const float lu = u.u1 - u.u0, lv = u.v1 - u.v0;
        if (!fits_one_object(config_, lu, lv, tall(config_, h.height) && tall(config_, f.height)))
          continue;
        if (narrow_host && !narrow_and_tall(config_, lu, lv, merged_[hi].height)) continue;
        if (best == hi && lu * lv >= best_area) continue;
        best = hi, best_gap = gap, best_union = u, best_heading = heading, best_area = lu * lv;
      }
    }
    if (best == nd) continue;
    Detection& h = merged_[best];
    const Eigen::Vector2f centre = h.position(true);
    const float ch = std::cos(best_heading), sh = std::sin(best_heading);
    h.yaw = best_heading;
    const float uc = 0.5f * (best_union.u0 + best_union.u1),
                vc = 0.5f * (best_union.v0 + best_union.v1);
    const float total = static_cast<float>(h.points + f.points);
    h.centroid =
        (h.centroid * static_cast<float>(h.points) + f.centroid * static_cast<float>(f.points)) /
        total;
    h.box_center = centre + Eigen::Vector2f(ch * uc - sh * vc, sh * uc + ch * vc);
    h.length = best_union.u1 - best_union.u0;
    h.width = best_union.v1 - best_union.v0;
    if (h.width > h.length) {
      std::swap(h.length, h.width);
      h.yaw = static_cast<float>(wrap_pi(h.yaw + std::numbers::pi / 2));
    }
    h.height = std::max(h.height, f.height);
    h.end_on = false;  // a union: its heading no longer points away from the sensor
    h.points += f.points;
    host_[best] = best_known || host_[best] == kBodyHost ? kBodyHost : kHost;
    if (own != nullptr) {
      merged_track_[static_cast<std::size_t>(det_match_[fi])] = 1;
      ++counters_.deleted_merged;
    }
    det_match_[fi] = kAbsorbed;
    ++counters_.absorbed_detections;
  }
}

void Tracker::merge_overlapping(std::int64_t stamp_ns) noexcept {
  if (config_.overlap_margin_m < 0) return;
  const auto margin = static_cast<float>(config_.overlap_margin_m);
  const auto person = [&](const Track& t) {
    return narrow_and_tall(config_, t.length, t.width, t.height);
  };
  const auto fits = [&](const Track& t) {
    return fits_one_object(config_, t.length, t.width, tall(config_, t.height));
  };
  const std::size_t n = live_.size();
  std::fill_n(merged_track_.begin(), n, std::uint8_t{0});
  // The tracks' x,y in one compact array for the pair loop (kept current when a is corrected).
  for (std::size_t i = 0; i < n; ++i) track_xy_[i] = slots_[live_[i]].x.head<2>();
  // The tracks sorted by x: the pairs within a's reach lie in a window of that order (a track
  // corrected below is moved to its new place).
  const auto before = [&](std::uint32_t p, std::uint32_t q) {
    return track_xy_[p].x() < track_xy_[q].x() || (track_xy_[p].x() == track_xy_[q].x() && p < q);
  };
  for (std::size_t i = 0; i < n; ++i) order_[i] = static_cast<std::uint32_t>(i);
  std::sort(order_.begin(), order_.begin() + static_cast<std::ptrdiff_t>(n), before);
  for (std::size_t k = 0; k < n; ++k) rank_[order_[k]] = static_cast<std::uint32_t>(k);
  const auto move_to_place = [&](std::uint32_t t) {
    std::size_t k = rank_[t];
    for (; k > 0 && before(t, order_[k - 1]); --k) {
      order_[k] = order_[k - 1];
      rank_[order_[k]] = static_cast<std::uint32_t>(k);
    }
    for (; k + 1 < n && before(order_[k + 1], t); ++k) {
      order_[k] = order_[k + 1];
      rank_[order_[k]] = static_cast<std::uint32_t>(k);
    }
    order_[k] = t;
    rank_[t] = static_cast<std::uint32_t>(k);
  };
  for (std::size_t i = 0; i < n; ++i) {
    if (merged_track_[i] != 0) continue;
    Slot& a = slots_[live_[i]];
    const bool narrow = person(a.track);  // takes only low tracks (legs) into its box
    // Both boxes must fit what one fragmented object's box may (a hedge, a wall or a canopy
    // beside a parked car does not), and a's changes only when it merges: it never will.
    if (!narrow && !fits(a.track)) continue;
    const float grow = narrow ? static_cast<float>(config_.absorb_narrow_gap_m) : margin;
    float reach = 0, ca = 1, sa = 0;  // of a's grown box; refreshed when a is corrected
    const auto shape = [&] {
      reach = 0.5f * std::hypot(a.track.length + 2 * grow, a.track.width + 2 * grow);
      ca = std::cos(a.track.yaw), sa = std::sin(a.track.yaw);
    };
    shape();
    // Tries the pair (a, track j); true when a was corrected (it moved).
    const auto pair = [&](std::size_t j) {
      if (j == i || merged_track_[j] != 0) return false;
      const float dx = static_cast<float>(track_xy_[j].x() - track_xy_[i].x()),
                  dy = static_cast<float>(track_xy_[j].y() - track_xy_[i].y());
      if (dx * dx + dy * dy > reach * reach) return false;  // outside the grown box's circle
      const Slot& b = slots_[live_[j]];
      if (person(b.track) ||
          (narrow ? b.track.height >= config_.absorb_keep_height_m : !older(a.track, b.track))) {
        return false;
      }
      if (std::abs(ca * dx + sa * dy) > 0.5f * a.track.length + grow ||
          std::abs(-sa * dx + ca * dy) > 0.5f * a.track.width + grow) {
        return false;
      }
      if (!narrow && (!fits(a.track) || !fits(b.track))) return false;
      // b is the same object as the older a: a keeps its id (and its velocity); if only b was
      // measured in this scan, b's measurement corrects a.
      bool moved = false;
      if (a.track.segment < 0 && b.measured >= 0) {
        // Learns the extent from any measurement, a known body's union too (unlike step 4).
        const auto bi = static_cast<std::size_t>(b.measured);
        Eigen::Matrix2d spread;
        float gap = 0;
        Eigen::Vector2f centre = Eigen::Vector2f::Zero();
        Detection m = merged_[bi];
        const bool is_piece = piece(a, m, bi, spread, gap, centre);
        if (is_piece) m.box_center = centre;
        correct(a, m, stamp_ns, true, is_piece ? &spread : nullptr, host_[bi] == 0);
        track_xy_[i] = a.x.head<2>();
        a.measured = b.measured;
        shape();
        moved = true;
      }
      merged_track_[j] = 1;
      ++counters_.deleted_overlap;
      return moved;
    };
    // The tracks from j = `from` on within reach along x (a margin above rounding: every pair
    // outside fails the circle test above), tried in the order of j as a scan of all pairs
    // would; when a moves, its remaining pairs are gathered again around its new place.
    for (std::size_t from = 0;;) {
      const double window = static_cast<double>(reach) * (1 + 1e-5), xi = track_xy_[i].x();
      std::size_t candidates = 0;
      for (std::size_t k = rank_[i]; k-- > 0 && xi - track_xy_[order_[k]].x() <= window;) {
        if (order_[k] >= from) candidate_[candidates++] = order_[k];
      }
      for (std::size_t k = rank_[i] + 1; k < n && track_xy_[order_[k]].x() - xi <= window; ++k) {
        if (order_[k] >= from) candidate_[candidates++] = order_[k];
      }
      std::sort(candidate_.begin(), candidate_.begin() + static_cast<std::ptrdiff_t>(candidates));
      bool moved = false;
      for (std::size_t c = 0; c < candidates && !moved; ++c) {
        moved = pair(candidate_[c]);
        from = candidate_[c] + 1;
      }
      if (!moved) break;
      move_to_place(static_cast<std::uint32_t>(i));
    }
  }
  std::size_t kept = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (merged_track_[i] != 0) {
      (void)free_.push_back(live_[i]);
    } else {
      live_[kept++] = live_[i];
    }
  }
  (void)live_.resize(kept);
}

void Tracker::assign(std::size_t nd, std::size_t nrows, std::size_t ncols) noexcept {
  // Union-find over rows [0, nrows) and columns [nrows, nrows + ncols).
  const std::size_t nodes = nrows + ncols;
  for (std::size_t i = 0; i < nodes; ++i) parent_[i] = static_cast<std::uint32_t>(i);
  const auto find = [&](std::uint32_t a) {
    while (parent_[a] != a) a = parent_[a] = parent_[parent_[a]];
    return a;
  };
  for (std::size_t ri = 0; ri < nrows; ++ri) {
    const float* costs = &pair_cost_[rows_[ri] * nd];
    for (std::size_t ci = 0; ci < ncols; ++ci) {
      if (costs[cols_[ci]] < 0) continue;
      const std::uint32_t a = find(static_cast<std::uint32_t>(ri)),
                          b = find(static_cast<std::uint32_t>(nrows + ci));
      if (a != b) parent_[std::max(a, b)] = std::min(a, b);  // the root is a component's first row
    }
  }
  // Components numbered by their first row; members listed in increasing order, rows of
  // component k at [start[2k], start[2k + 1]), its columns at [start[2k + 1], start[2k + 2]).
  std::size_t components = 0;
  for (std::size_t i = 0; i < nodes; ++i) {
    const std::uint32_t root = find(static_cast<std::uint32_t>(i));
    component_[i] = root == i ? static_cast<std::uint32_t>(components++) : component_[root];
  }
  std::fill_n(component_start_.begin(), 2 * components + 1, 0u);
  for (std::size_t i = 0; i < nodes; ++i)
    ++component_start_[2 * component_[i] + (i < nrows ? 1 : 2)];
  for (std::size_t k = 1; k <= 2 * components; ++k) component_start_[k] += component_start_[k - 1];
  for (std::size_t i = 0; i < nodes; ++i) {
    component_members_[component_start_[2 * component_[i] + (i < nrows ? 0 : 1)]++] =
        static_cast<std::uint32_t>(i < nrows ? i : i - nrows);
  }
  for (std::size_t k = 2 * components; k > 0; --k) component_start_[k] = component_start_[k - 1];
  component_start_[0] = 0;
  bool failed = false;
  for (std::size_t k = 0; k < components; ++k) {
    const std::uint32_t* rows = &component_members_[component_start_[2 * k]];
    const std::uint32_t* cols = &component_members_[component_start_[2 * k + 1]];
    const std::size_t nr = component_start_[2 * k + 1] - component_start_[2 * k];
    const std::size_t nc = component_start_[2 * k + 2] - component_start_[2 * k + 1];
    if (nr == 1 && nc == 1) {  // one allowed pair: it is the match
      det_match_[cols_[cols[0]]] = static_cast<std::int32_t>(rows_[rows[0]]);
      continue;
    }
    for (std::size_t ri = 0; ri < nr; ++ri) {
      const float* costs = &pair_cost_[rows_[rows[ri]] * nd];
      for (std::size_t ci = 0; ci < nc; ++ci) {
        const float c = costs[cols_[cols[ci]]];
        cost_[ri * nc + ci] = c < 0 ? kForbidden : static_cast<double>(c);
      }
    }
    if (!solver_.solve({cost_.data(), nr * nc}, nr, nc, {row_to_col_.data(), nr})) {
      failed = true;
      continue;
    }
    for (std::size_t ri = 0; ri < nr; ++ri) {
      const int ci = row_to_col_[ri];
      if (ci < 0 || cost_[ri * nc + static_cast<std::size_t>(ci)] >= kForbidden) continue;
      det_match_[cols_[cols[ci]]] = static_cast<std::int32_t>(rows_[rows[ri]]);
    }
  }
  if (failed) ++counters_.solver_failures;
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
  // 1. Predict every track to the scan stamp.
  double dt = 0;
  if (have_stamp_) {
    dt = static_cast<double>(stamp_ns - last_stamp_ns_) * 1e-9;
    if (dt <= 0) ++counters_.stamp_regressions;
  }
  if (!have_stamp_ || dt > 0) last_stamp_ns_ = stamp_ns;
  have_stamp_ = true;
  for (const std::uint32_t i : live_) {
    predict(slots_[i], dt);
    slots_[i].measured = -1;
    Track& t = slots_[i].track;
    t.segment = -1;
    if (dt > 0) ++t.age;
  }

  // 2. Gate every (track, detection) pair; keep rows and columns with at least one allowed pair.
  const std::size_t nt = live_.size(), nd = detections.size();
  const double r = config_.measurement_std_m * config_.measurement_std_m;
  std::size_t nrows = 0, ncols = 0;
  std::fill_n(col_of_det_.begin(), nd, -1);
  std::fill_n(det_match_.begin(), nd, -1);
  // A pair farther apart than the distance gate along x or y fails it (cheap test first; the
  // margin keeps it exact under rounding).
  const double gate_axis = config_.gate_distance_m * (1 + 1e-9);
  for (std::size_t di = 0; di < nd; ++di) {
    positions_[di] = detections[di].position(config_.position_from_box).cast<double>();
  }
  for (std::size_t ti = 0; ti < nt; ++ti) {
    const Slot& s = slots_[live_[ti]];
    Eigen::Matrix2d sxy = s.p.topLeftCorner<2, 2>();
    sxy.diagonal() += Eigen::Vector2d(r, r);
    const Eigen::Matrix2d sinv = sxy.inverse();
    const Eigen::Vector2d predicted = s.x.head<2>();
    float* costs = &pair_cost_[ti * nd];
    bool any = false;
    // A track of known extent measures an end-on detection at its anchored centre, up to half
    // its length from the box's.
    const bool known = knows_extent(config_, s.known_length);
    const double reach = known ? gate_axis + 0.5 * s.known_length : gate_axis;
    for (std::size_t di = 0; di < nd; ++di) {
      Eigen::Vector2d e = positions_[di] - predicted;
      costs[di] = -1.0f;
      if (!(std::abs(e.x()) <= reach && std::abs(e.y()) <= reach)) continue;
      Eigen::Vector2f centre = Eigen::Vector2f::Zero();
      Eigen::Matrix2d spread;
      float gap = 0;
      double m2 = 0;
      if (known && piece(s, detections[di], di, spread, gap, centre)) {
        // A piece of the known body: its centre, with the spread of where in the body it lies;
        // the distance gate applies to the nearest centre at which the body covers it.
        if (!(gap <= config_.gate_distance_m)) continue;
        e = centre.cast<double>() - predicted;
        m2 = e.dot((sxy + spread).inverse() * e);
        if (!(m2 <= config_.gate_mahalanobis_sq)) continue;
      } else {
        if (known &&
            anchored_centre(config_, s.known_length, s.known_yaw, detections[di], centre)) {
          e = centre.cast<double>() - predicted;
        }
        if (!(std::abs(e.x()) <= gate_axis && std::abs(e.y()) <= gate_axis)) continue;
        m2 = e.dot(sinv * e);
        if (!(m2 <= config_.gate_mahalanobis_sq && e.norm() <= config_.gate_distance_m)) continue;
      }
      costs[di] = static_cast<float>(m2);
      any = true;
      if (col_of_det_[di] < 0) {
        col_of_det_[di] = static_cast<std::int32_t>(ncols);
        cols_[ncols++] = static_cast<std::uint32_t>(di);
      }
    }
    if (any) rows_[nrows++] = static_cast<std::uint32_t>(ti);
  }

  // 3. Global assignment over the gated sub-matrix. Forbidden pairs cost kForbidden, so the
  //    solution keeps as many allowed pairs as possible, then the smallest total distance.
  //    Tracks and detections that share no chain of allowed pairs never compete: the problem
  //    is solved per connected component of the allowed pairs (the same optimum, on small
  //    matrices; most components are one track and one detection).
  if (nrows > 0) assign(nd, nrows, ncols);

  // 4. Fragments join the measurement of a matched track beside them; update matched tracks
  //    (the others are marked missed below).
  absorb_fragments(detections);
  for (std::size_t di = 0; di < nd; ++di) {
    if (det_match_[di] >= 0) {
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
  // 5. Prune: misses and uncertainty (compacting the live list in place, order kept).
  std::size_t kept = 0;
  for (std::size_t ti = 0; ti < nt; ++ti) {
    const std::uint32_t index = live_[ti];
    Slot& s = slots_[index];
    Track& t = s.track;
    bool remove = merged_track_[ti] != 0;  // its fragment joined an older track's measurement
    if (!remove && t.segment < 0) {
      ++t.misses;
      if (t.state == TrackState::kTentative) {
        if (t.misses > config_.tentative_max_misses) {
          remove = true;
          ++counters_.deleted_tentative;
        }
      } else {
        t.state = TrackState::kCoasting;
        if (position_std(s.p) > config_.max_position_std_m) {
          remove = true;
          ++counters_.deleted_uncertain;
        } else if (t.misses > config_.max_coast_scans) {
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
  // 6. Unmatched detections (not absorbed) spawn tentative tracks.
  for (std::size_t di = 0; di < nd; ++di) {
    if (det_match_[di] == kUnmatched && spawn(detections[di], stamp_ns)) {
      slots_[live_.back()].measured = static_cast<std::int32_t>(di);
    }
  }

  // 7. Tracks inside an older track's box are merged into it.
  merge_overlapping(stamp_ns);

  // 8. Report.
  out.stamp_ns = stamp_ns;
  out.tracks.clear();
  for (const std::uint32_t i : live_) {
    Slot& s = slots_[i];
    Track& t = s.track;
    t.position = s.x.head<3>().cast<float>();
    t.velocity = s.x.tail<2>().cast<float>();
    t.position_std_m = static_cast<float>(position_std(s.p));
    if (!out.tracks.push_back(t)) break;
  }
  out.counters = counters_;
}

}  // namespace stac::tracking
