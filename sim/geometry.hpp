// Ray casting against the primitives the simulated world is built from, in double precision.
// A ray is origin + t * direction with t >= 0; every hit function returns the smallest t > eps
// (or +inf) and the surface normal there.
#pragma once

#include <cmath>
#include <limits>

namespace stac::sim {

struct V3 {
  double x = 0, y = 0, z = 0;
};
inline V3 operator+(V3 a, V3 b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
inline V3 operator-(V3 a, V3 b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
inline V3 operator*(V3 a, double s) {
  return {a.x * s, a.y * s, a.z * s};
}
inline double dot(V3 a, V3 b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
inline double norm(V3 a) {
  return std::sqrt(dot(a, a));
}

inline constexpr double kNoHit = std::numeric_limits<double>::infinity();

struct Ray {
  V3 origin;
  V3 direction;  // unit length
};

struct Hit {
  double t = kNoHit;
  V3 normal;  // unit, facing the ray origin
};

// A planar pose: position (z is the base height) and heading about z, with its cos/sin.
struct Pose {
  double x = 0, y = 0, z = 0, yaw = 0;
  double c = 1, s = 0;  // cos(yaw), sin(yaw): set by with_trig()
  Pose with_trig() const {
    Pose p = *this;
    p.c = std::cos(yaw);
    p.s = std::sin(yaw);
    return p;
  }
  V3 to_local(V3 p) const {  // world point -> frame of this pose
    const double dx = p.x - x, dy = p.y - y;
    return {c * dx + s * dy, -s * dx + c * dy, p.z - z};
  }
  V3 rotate_to_local(V3 v) const { return {c * v.x + s * v.y, -s * v.x + c * v.y, v.z}; }
  V3 rotate_to_world(V3 v) const { return {c * v.x - s * v.y, s * v.x + c * v.y, v.z}; }
};

// Axis-aligned box [lo, hi] in the ray's frame.
Hit hit_box(const Ray& r, V3 lo, V3 hi);
// Vertical cylinder of radius `radius` around (cx, cy), z in [z0, z1], capped.
Hit hit_cylinder(const Ray& r, double cx, double cy, double radius, double z0, double z1);
// Axis-aligned ellipsoid with centre c and semi-axes a.
Hit hit_ellipsoid(const Ray& r, V3 c, V3 a);
// A capsule-like limb: a cylinder between two points (no caps), radius `radius`.
Hit hit_segment(const Ray& r, V3 p0, V3 p1, double radius);

}  // namespace stac::sim
