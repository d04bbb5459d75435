// End-on vehicles and known bodies (docs/tracking.md): a face across the sensor's ray completed
// into a vehicle's box; a tall track's remembered length measuring its faces and pieces.
#include "perception/tracking/body.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "perception/tracking/shapes.hpp"
#include "perception/tracking/slot.hpp"
#include "perception/tracking/tracker.hpp"

namespace stac::tracking {

using namespace shapes;  // NOLINT(google-build-using-namespace): the tracker's own box rules

// Known extent (TrackerConfig::body.memory_length_m): the centre of the body, `known` m long
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

namespace {

// Known extent (TrackerConfig::body.gating): tall detection d as a piece of the known body
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
// object.tall_height_m, a person, not shorter than the body, longer than it along the heading,
// or not along the track's box (within 30 degrees).
template <class Occluded>
bool piece_of_body(const TrackerConfig& c, float known, float known_single, float known_width,
                   float track_yaw, const Eigen::Vector2f& predicted, const Detection& d,
                   Eigen::Matrix2d& spread, float& gap, Eigen::Vector2f& centre,
                   Occluded&& occluded) {
  if (!c.body.gating || !knows_extent(c, known) || !c.position_from_box || d.end_on ||
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

}  // namespace

bool complete_end_on(const TrackerConfig& c, const Eigen::Vector2f& sensor_xy,
                     Detection& d) noexcept {
  if (c.end_on.length_m <= 0 || !d.box_center.allFinite()) return false;
  const Eigen::Vector2f ray = d.box_center - sensor_xy;
  const float range = ray.norm();
  if (!(range > 1e-3f) || range < c.end_on.min_range_m) return false;
  const Eigen::Vector2f r = ray / range;
  // The long side must lie across the ray (within 30 degrees of perpendicular).
  const float along = std::abs(r.x() * std::cos(d.yaw) + r.y() * std::sin(d.yaw));
  if (along > 0.5f || d.length < c.end_on.min_width_m || d.length > c.end_on.max_width_m ||
      d.width > c.end_on.max_depth_m || d.height < c.end_on.min_height_m) {
    return false;
  }
  const auto length = static_cast<float>(c.end_on.length_m);
  if (length <= d.width) return false;
  d.box_center += r * (0.5f * (length - d.width));
  d.width = d.length;
  d.length = length;
  d.yaw = std::atan2(r.y(), r.x());
  d.end_on = true;
  return true;
}

int Tracker::hidden_end(const Slot& s, const Detection& d, float u0, float u1,
                        float vc) const noexcept {
  if (!have_sensor_) return 0;
  const Eigen::Vector2f predicted = s.kf.x.head<2>().cast<float>();
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
      s.kf.x.head<2>().cast<float>(), m, spread, gap, centre,
      [&](float u0, float u1, float vc) { return hidden_end(s, scan_[di], u0, u1, vc); });
}

bool Tracker::inside_known_body(const Slot& s, const Detection& f) const noexcept {
  if (config_.fragments.known_margin_m < 0 || !knows_extent(config_, s.known_length)) return false;
  const auto margin = static_cast<float>(config_.fragments.known_margin_m);
  const Extent e = extent_in(f, s.kf.x.head<2>().cast<float>(), s.known_yaw);
  const float hl = 0.5f * s.known_length + margin, hw = 0.5f * s.track.width + margin;
  return e.u0 >= -hl && e.u1 <= hl && e.v0 >= -hw && e.v1 <= hw;
}

}  // namespace stac::tracking
