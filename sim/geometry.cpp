#include "sim/geometry.hpp"

#include <algorithm>

namespace stac::sim {
namespace {

constexpr double kEps = 1e-6;

V3 facing(V3 n, const Ray& r) {
  return dot(n, r.direction) > 0 ? n * -1.0 : n;
}

}  // namespace

Hit hit_box(const Ray& r, V3 lo, V3 hi) {
  const double o[3] = {r.origin.x, r.origin.y, r.origin.z};
  const double d[3] = {r.direction.x, r.direction.y, r.direction.z};
  const double l[3] = {lo.x, lo.y, lo.z}, h[3] = {hi.x, hi.y, hi.z};
  double t0 = -kNoHit, t1 = kNoHit;
  int axis0 = 0, axis1 = 0;
  for (int a = 0; a < 3; ++a) {
    if (std::abs(d[a]) < 1e-12) {
      if (o[a] < l[a] || o[a] > h[a]) return {};
      continue;
    }
    double ta = (l[a] - o[a]) / d[a], tb = (h[a] - o[a]) / d[a];
    if (ta > tb) std::swap(ta, tb);
    if (ta > t0) t0 = ta, axis0 = a;
    if (tb < t1) t1 = tb, axis1 = a;
    if (t0 > t1) return {};
  }
  double t = t0;
  int axis = axis0;
  if (t <= kEps) t = t1, axis = axis1;  // origin inside: the exit face
  if (t <= kEps || t == kNoHit) return {};
  V3 n;
  (axis == 0 ? n.x : axis == 1 ? n.y : n.z) = 1.0;
  return {t, facing(n, r)};
}

Hit hit_cylinder(const Ray& r, double cx, double cy, double radius, double z0, double z1) {
  Hit best;
  const double ox = r.origin.x - cx, oy = r.origin.y - cy;
  const double a = r.direction.x * r.direction.x + r.direction.y * r.direction.y;
  if (a > 1e-12) {
    const double b = 2 * (ox * r.direction.x + oy * r.direction.y);
    const double c = ox * ox + oy * oy - radius * radius;
    const double disc = b * b - 4 * a * c;
    if (disc >= 0) {
      const double sq = std::sqrt(disc);
      for (double t : {(-b - sq) / (2 * a), (-b + sq) / (2 * a)}) {
        const double z = r.origin.z + t * r.direction.z;
        if (t > kEps && z >= z0 && z <= z1) {
          const V3 n{(ox + t * r.direction.x) / radius, (oy + t * r.direction.y) / radius, 0};
          best = {t, facing(n, r)};
          break;
        }
      }
    }
  }
  if (std::abs(r.direction.z) > 1e-12) {  // caps
    for (double zc : {z0, z1}) {
      const double t = (zc - r.origin.z) / r.direction.z;
      if (t <= kEps || t >= best.t) continue;
      const double px = ox + t * r.direction.x, py = oy + t * r.direction.y;
      if (px * px + py * py <= radius * radius) best = {t, facing(V3{0, 0, 1}, r)};
    }
  }
  return best;
}

Hit hit_ellipsoid(const Ray& r, V3 c, V3 a) {
  // Scale space so the ellipsoid is the unit sphere.
  const V3 o{(r.origin.x - c.x) / a.x, (r.origin.y - c.y) / a.y, (r.origin.z - c.z) / a.z};
  const V3 d{r.direction.x / a.x, r.direction.y / a.y, r.direction.z / a.z};
  const double qa = dot(d, d), qb = 2 * dot(o, d), qc = dot(o, o) - 1;
  const double disc = qb * qb - 4 * qa * qc;
  if (disc < 0) return {};
  const double sq = std::sqrt(disc);
  double t = (-qb - sq) / (2 * qa);
  if (t <= kEps) t = (-qb + sq) / (2 * qa);
  if (t <= kEps) return {};
  const V3 p = o + d * t;
  V3 n{p.x / a.x, p.y / a.y, p.z / a.z};
  n = n * (1.0 / norm(n));
  return {t, facing(n, r)};
}

Hit hit_segment(const Ray& r, V3 p0, V3 p1, double radius) {
  // Infinite cylinder around the axis, then clipped to the segment.
  const V3 axis = p1 - p0;
  const double len = norm(axis);
  if (len < 1e-9) return {};
  const V3 u = axis * (1.0 / len);
  const V3 w = r.origin - p0;
  const V3 dp = r.direction - u * dot(r.direction, u);
  const V3 wp = w - u * dot(w, u);
  const double a = dot(dp, dp), b = 2 * dot(dp, wp), c = dot(wp, wp) - radius * radius;
  if (a < 1e-12) return {};
  const double disc = b * b - 4 * a * c;
  if (disc < 0) return {};
  const double sq = std::sqrt(disc);
  for (double t : {(-b - sq) / (2 * a), (-b + sq) / (2 * a)}) {
    if (t <= kEps) continue;
    const V3 p = r.origin + r.direction * t;
    const double s = dot(p - p0, u);
    if (s < 0 || s > len) continue;
    V3 n = (p - p0) - u * s;
    n = n * (1.0 / norm(n));
    return {t, facing(n, r)};
  }
  return {};
}

}  // namespace stac::sim
