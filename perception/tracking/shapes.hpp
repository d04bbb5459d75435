// The box rules the tracker's parts share (internal to perception/tracking): box angles, extents
// along a heading, what one object may span, people, tall vehicles (docs/tracking.md).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "perception/tracking/track.hpp"
#include "perception/tracking/tracker.hpp"

namespace stac::tracking::shapes {

// Angle difference wrapped to [-pi/2, pi/2): box headings are defined modulo pi.
inline double box_angle_diff(double a, double b) {
  double d = std::fmod(a - b, std::numbers::pi);
  if (d >= std::numbers::pi / 2) d -= std::numbers::pi;
  if (d < -std::numbers::pi / 2) d += std::numbers::pi;
  return d;
}

inline double wrap_pi(double a) {
  a = std::fmod(a + std::numbers::pi, 2 * std::numbers::pi);
  if (a < 0) a += 2 * std::numbers::pi;
  return a - std::numbers::pi;
}

// A box's extent along the axes u = (cos h, sin h), v = (-sin h, cos h) of heading h.
struct Extent {
  float u0, u1, v0, v1;
};

// The smallest extent holding both.
inline Extent hull(const Extent& a, const Extent& b) {
  return {std::min(a.u0, b.u0), std::max(a.u1, b.u1), std::min(a.v0, b.v0), std::max(a.v1, b.v1)};
}

// The extent of the box (box_centre, length x width at yaw) about `centre` along heading h.
inline Extent extent_in(const Eigen::Vector2f& box_centre, float length, float width, float yaw,
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

inline Extent extent_in(const Detection& d, const Eigen::Vector2f& centre, float h) {
  return extent_in(d.position(true), d.length, d.width, d.yaw, centre, h);
}

// Whether a box of this height is a tall vehicle's (a truck's: object.tall_height_m).
inline bool tall(const TrackerConfig& c, float height) {
  return c.object.tall_height_m > 0 && height >= c.object.tall_height_m;
}

// The longest box one fragmented object may span: object.max_length_m, or object.tall_length_m
// (if longer) for a tall one.
inline double longest_object(const TrackerConfig& c, bool tall_object) {
  return tall_object ? std::max(c.object.max_length_m, c.object.tall_length_m)
                     : c.object.max_length_m;
}

// A box that fits what one fragmented object may span (longest_object x object.max_width_m).
inline bool fits_one_object(const TrackerConfig& c, float length, float width, bool tall_object) {
  return std::max(length, width) <= longest_object(c, tall_object) &&
         std::min(length, width) <= c.object.max_width_m;
}

// Which of two tracks is older: more hits, then the lower id (the merges keep the older).
inline bool older(const Track& a, const Track& b) {
  return a.hits > b.hits || (a.hits == b.hits && a.id < b.id);
}

// People and bicyclists: never joined to other objects (TrackerConfig::person).
inline bool narrow_and_tall(const TrackerConfig& c, float length, float width, float height) {
  const PersonConfig& p = c.person;
  const float wide = std::min(length, width), longest = std::max(length, width);
  if (p.strip_width_m > 0 && wide <= p.strip_width_m && longest >= p.strip_length_m) {
    return false;  // a flat strip: a car's side or a wall seen edge-on, not a person
  }
  return longest <= p.max_length_m && ((wide <= p.max_width_m && height >= p.min_height_m) ||
                                       (wide <= p.wide_m && height >= p.wide_min_height_m));
}

// What a measurement tells a track of its known extent (body.memory_length_m): its length
// when it is a tall box that fits one object, else 0.
inline float tall_length(const TrackerConfig& c, const Detection& d) {
  return tall(c, d.height) && fits_one_object(c, d.length, d.width, true) ? d.length : 0.0f;
}

// Whether a track that remembers `known` m measures end-on faces with it (memory on and long
// enough).
inline bool knows_extent(const TrackerConfig& c, float known) {
  return c.body.memory_length_m > 0 && known >= c.body.memory_length_m;
}

}  // namespace stac::tracking::shapes
