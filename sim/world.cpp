#include "sim/world.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace stac::sim {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

Hit nearer(Hit a, Hit b) {
  return b.t < a.t ? b : a;
}

// Legs and arms of a walking person of height h, phase in radians, swing 0..1 (0 standing).
Hit hit_walker(const Ray& r, double h, double phase, double swing) {
  Hit best = hit_ellipsoid(r, {0, 0, 0.70 * h}, {0.13, 0.21, 0.17 * h});            // torso
  best = nearer(best, hit_ellipsoid(r, {0, 0, 0.93 * h}, {0.10, 0.09, 0.07 * h}));  // head
  const double stride = 0.32 * swing;
  const double sin_phase = std::sin(phase);
  for (int side : {-1, 1}) {
    const double s = side * sin_phase;
    best = nearer(best,
                  hit_segment(r, {0, side * 0.1, 0.52 * h}, {stride * s, side * 0.1, 0.04}, 0.07));
    best = nearer(best, hit_segment(r, {0, side * 0.22, 0.80 * h},
                                    {-0.7 * stride * s, side * 0.25, 0.46 * h}, 0.045));
  }
  return best;
}

// A bicycle along local x, wheels of radius 0.35 at x = +-0.53, centred at lateral offset y.
Hit hit_bicycle(const Ray& r, double y) {
  Hit best = hit_ellipsoid(r, {0.53, y, 0.35}, {0.35, 0.025, 0.35});
  best = nearer(best, hit_ellipsoid(r, {-0.53, y, 0.35}, {0.35, 0.025, 0.35}));
  best = nearer(best, hit_segment(r, {-0.53, y, 0.35}, {0.05, y, 0.85}, 0.03));  // seat stay
  best = nearer(best, hit_segment(r, {0.05, y, 0.85}, {0.45, y, 0.85}, 0.03));   // top tube
  best = nearer(best, hit_segment(r, {0.45, y - 0.25, 1.0}, {0.45, y + 0.25, 1.0}, 0.02));  // bars
  return best;
}

Hit hit_wheels(const Ray& r, double length, double width, double radius) {
  Hit best;
  for (double x : {-0.32 * length, 0.32 * length}) {
    for (int side : {-1, 1}) {
      const double y_out = side * width / 2, y_in = side * (width / 2 - 0.22);
      best = nearer(best, hit_segment(r, {x, y_in, radius}, {x, y_out, radius}, radius));
    }
  }
  return best;
}

}  // namespace

bool class_from_name(std::string_view name, ObjectClass& out) noexcept {
  for (auto c = static_cast<int>(ObjectClass::kCar); c <= static_cast<int>(ObjectClass::kClutter);
       ++c) {
    if (class_name(static_cast<ObjectClass>(c)) != name) continue;
    out = static_cast<ObjectClass>(c);
    return true;
  }
  return false;
}

std::string_view class_name(ObjectClass c) noexcept {
  switch (c) {
    case ObjectClass::kCar:
      return "car";
    case ObjectClass::kPedestrian:
      return "pedestrian";
    case ObjectClass::kBicyclist:
      return "bicyclist";
    case ObjectClass::kBuilding:
      return "building";
    case ObjectClass::kWall:
      return "wall";
    case ObjectClass::kFence:
      return "fence";
    case ObjectClass::kTree:
      return "tree";
    case ObjectClass::kBush:
      return "bush";
    case ObjectClass::kPole:
      return "pole";
    case ObjectClass::kSign:
      return "sign";
    case ObjectClass::kBin:
      return "bin";
    case ObjectClass::kClutter:
      break;
  }
  return "clutter";
}

bool is_foreground(ObjectClass c) noexcept {
  return c == ObjectClass::kCar || c == ObjectClass::kPedestrian || c == ObjectClass::kBicyclist;
}

Pose Trajectory::pose_at(double t) const {
  if (points.empty()) return {};
  if (points.size() == 1 || t <= points.front().t) {
    Pose p{points.front().x, points.front().y, 0, fixed_yaw};
    if (points.size() > 1) {
      for (std::size_t i = 1; i < points.size(); ++i) {
        const double dx = points[i].x - points[0].x, dy = points[i].y - points[0].y;
        if (dx * dx + dy * dy > 1e-9) {
          p.yaw = std::atan2(dy, dx);
          break;
        }
      }
    }
    return p;
  }
  std::size_t i = 1;
  while (i < points.size() && points[i].t < t) ++i;
  // Heading: of the segment being travelled, else of the last moving segment before it.
  double yaw = fixed_yaw;
  for (std::size_t k = std::min(i, points.size() - 1); k >= 1; --k) {
    const double dx = points[k].x - points[k - 1].x, dy = points[k].y - points[k - 1].y;
    if (dx * dx + dy * dy > 1e-9) {
      yaw = std::atan2(dy, dx);
      break;
    }
  }
  if (i == points.size()) return {points.back().x, points.back().y, 0, yaw};
  const Waypoint& a = points[i - 1];
  const Waypoint& b = points[i];
  const double f = b.t > a.t ? (t - a.t) / (b.t - a.t) : 1.0;
  return {a.x + f * (b.x - a.x), a.y + f * (b.y - a.y), 0, yaw};
}

V3 Trajectory::velocity_at(double t) const {
  for (std::size_t i = 1; i < points.size(); ++i) {
    if (t >= points[i - 1].t && t < points[i].t) {
      const double dt = points[i].t - points[i - 1].t;
      return {(points[i].x - points[i - 1].x) / dt, (points[i].y - points[i - 1].y) / dt, 0};
    }
  }
  return {};
}

World::World(GroundConfig ground, std::vector<Actor> actors)
    : ground_(ground), actors_(std::move(actors)) {
  radius_.reserve(actors_.size());
  for (const Actor& a : actors_) {
    double r = 0.5 * std::hypot(a.size.x, a.size.y) + 0.3;
    if (a.shape == Shape::kWalkerWithBike) r += 1.0;
    radius_.push_back(r);
  }
}

double World::actor_radius(std::size_t i) const noexcept {
  return radius_[i];
}

double World::terrain_height(double x, double y) const noexcept {
  return ground_.slope_x * x + ground_.slope_y * y +
         ground_.wave_amplitude * std::sin(kTwoPi * x / ground_.wave_length);
}

double World::ground_height(double x, double y) const noexcept {
  const bool on_road = !ground_.has_road ||
                       std::abs(y - ground_.road_y) < ground_.road_half_width ||
                       std::abs(x - ground_.cross_road_x) < ground_.cross_half_width;
  return terrain_height(x, y) + (on_road ? 0.0 : ground_.curb_height);
}

Pose World::actor_pose(std::size_t i, double t) const {
  Pose p = actors_[i].path.pose_at(t);
  p.z = ground_height(p.x, p.y);
  return p.with_trig();
}

Hit World::hit_ground(const Ray& r) const {
  const GroundConfig& g = ground_;
  const double k = kTwoPi / g.wave_length;
  auto solve = [&](double raise) -> double {
    // Newton on f(t) = z(t) - h(x(t), y(t)), from the plane without the wave.
    const double den0 = r.direction.z - g.slope_x * r.direction.x - g.slope_y * r.direction.y;
    if (std::abs(den0) < 1e-9) return kNoHit;
    double t = (g.slope_x * r.origin.x + g.slope_y * r.origin.y + raise - r.origin.z) / den0;
    if (t <= 0) return kNoHit;
    for (int it = 0; it < 6; ++it) {
      const V3 p = r.origin + r.direction * t;
      const double f = p.z - terrain_height(p.x, p.y) - raise;
      const double df = r.direction.z - g.slope_x * r.direction.x - g.slope_y * r.direction.y -
                        g.wave_amplitude * k * std::cos(k * p.x) * r.direction.x;
      if (std::abs(df) < 1e-9) return kNoHit;
      t -= f / df;
      if (std::abs(f) < 1e-7) break;
    }
    const V3 p = r.origin + r.direction * t;
    if (t <= 0 || std::abs(p.z - terrain_height(p.x, p.y) - raise) > 1e-4) return kNoHit;
    return t;
  };
  auto on_road = [&](const V3& p) {
    return !g.has_road || std::abs(p.y - g.road_y) < g.road_half_width ||
           std::abs(p.x - g.cross_road_x) < g.cross_half_width;
  };
  auto normal_at = [&](const V3& p) {
    const double hx = g.slope_x + g.wave_amplitude * k * std::cos(k * p.x);
    V3 n{-hx, -g.slope_y, 1.0};
    return n * (1.0 / norm(n));
  };
  Hit best;
  const double t_road = solve(0.0);
  if (t_road < kNoHit && on_road(r.origin + r.direction * t_road))
    best = {t_road, normal_at(r.origin + r.direction * t_road)};
  if (!g.has_road) return best;
  const double t_walk = solve(g.curb_height);
  if (t_walk < best.t && !on_road(r.origin + r.direction * t_walk)) {
    best = {t_walk, normal_at(r.origin + r.direction * t_walk)};
  }
  // Curb faces: the vertical steps between road and sidewalk.
  auto face = [&](double plane, bool along_x) {
    const double o = along_x ? r.origin.y : r.origin.x;
    const double d = along_x ? r.direction.y : r.direction.x;
    if (std::abs(d) < 1e-12) return;
    const double t = (plane - o) / d;
    if (t <= 1e-6 || t >= best.t) return;
    const V3 p = r.origin + r.direction * t;
    const double base = terrain_height(p.x, p.y);
    if (p.z < base || p.z > base + g.curb_height) return;
    if (along_x && std::abs(p.x - g.cross_road_x) < g.cross_half_width) return;
    if (!along_x && std::abs(p.y - g.road_y) < g.road_half_width) return;
    V3 n = along_x ? V3{0, d > 0 ? -1.0 : 1.0, 0} : V3{d > 0 ? -1.0 : 1.0, 0, 0};
    best = {t, n};
  };
  face(g.road_y - g.road_half_width, true);
  face(g.road_y + g.road_half_width, true);
  face(g.cross_road_x - g.cross_half_width, false);
  face(g.cross_road_x + g.cross_half_width, false);
  return best;
}

Hit World::hit_actor_local(const Actor& a, const Ray& r, double t, bool& translucent) const {
  const double len = a.size.x, wid = a.size.y, hgt = a.size.z;
  translucent = false;
  switch (a.shape) {
    case Shape::kBox:
      return hit_box(r, {-len / 2, -wid / 2, 0}, {len / 2, wid / 2, hgt});
    case Shape::kSedan: {
      Hit h = hit_box(r, {-len / 2, -wid / 2, 0.30}, {len / 2, wid / 2, 0.62 * hgt});
      h = nearer(h,
                 hit_box(r, {-0.33 * len, -0.43 * wid, 0.62 * hgt}, {0.17 * len, 0.43 * wid, hgt}));
      return nearer(h, hit_wheels(r, len, wid, 0.32));
    }
    case Shape::kVan: {
      Hit h = hit_box(r, {-len / 2, -wid / 2, 0.35}, {len / 2, wid / 2, hgt});
      return nearer(h, hit_wheels(r, len, wid, 0.34));
    }
    case Shape::kTruck: {
      Hit h = hit_box(r, {len / 2 - 2.3, -wid / 2, 0.5}, {len / 2, wid / 2, 3.0});          // cab
      h = nearer(h, hit_box(r, {-len / 2, -wid / 2, 1.0}, {len / 2 - 2.5, wid / 2, hgt}));  // cargo
      return nearer(h, hit_wheels(r, len, wid, 0.5));
    }
    case Shape::kWalker:
    case Shape::kWalkerWithSuitcase:
    case Shape::kWalkerWithBike: {
      const V3 v = a.path.velocity_at(t);
      const double speed = std::hypot(v.x, v.y);
      const double phase = a.phase + kTwoPi * t * speed / 1.4;  // 1.4 m per gait cycle
      const double swing = std::min(speed / 1.4, 1.0);
      if (a.shape == Shape::kWalkerWithBike) {  // walker at y = -0.3, the bike at y = +0.35
        const Ray shifted{r.origin + V3{0, 0.3, 0}, r.direction};
        return nearer(hit_walker(shifted, hgt, phase, swing), hit_bicycle(r, 0.35));
      }
      Hit h = hit_walker(r, hgt, phase, swing);
      if (a.shape == Shape::kWalkerWithSuitcase) {
        h = nearer(h, hit_box(r, {-0.45, -0.42, 0.02}, {-0.12, -0.22, 0.62}));
      }
      return h;
    }
    case Shape::kCyclist: {
      const V3 v = a.path.velocity_at(t);
      const double speed = std::hypot(v.x, v.y);
      const double crank = a.phase + kTwoPi * t * speed / 4.5;  // 4.5 m per crank turn
      Hit h = hit_bicycle(r, 0.0);
      h = nearer(h, hit_ellipsoid(r, {0.05, 0, 1.25}, {0.24, 0.19, 0.27}));  // torso, leaning
      h = nearer(h, hit_ellipsoid(r, {0.28, 0, 1.62}, {0.11, 0.10, 0.13}));  // head
      for (int side : {-1, 1}) {
        const double c = crank + (side > 0 ? 0.0 : std::numbers::pi);
        const V3 foot{0.17 * std::cos(c), side * 0.13, 0.35 + 0.17 * std::sin(c)};
        h = nearer(h, hit_segment(r, {-0.05, side * 0.12, 0.95}, foot, 0.07));  // leg
        h = nearer(h, hit_segment(r, {0.12, side * 0.2, 1.4}, {0.45, side * 0.25, 1.0}, 0.045));
      }
      return h;
    }
    case Shape::kTree: {
      Hit h = hit_cylinder(r, 0, 0, 0.18, 0, 0.45 * hgt);
      bool crown = false;
      const Hit c = hit_ellipsoid(r, {0, 0, 0.68 * hgt}, {len / 2, wid / 2, 0.32 * hgt});
      if (c.t < h.t) h = c, crown = true;
      translucent = crown;
      return h;
    }
    case Shape::kBush:
      translucent = true;
      return hit_ellipsoid(r, {0, 0, hgt / 2}, {len / 2, wid / 2, hgt / 2});
    case Shape::kPole:
      return hit_cylinder(r, 0, 0, std::max(0.05, len / 2), 0, hgt);
    case Shape::kSign: {
      Hit h = hit_cylinder(r, 0, 0, 0.04, 0, hgt);
      return nearer(h, hit_box(r, {-0.03, -wid / 2, hgt - 0.75}, {0.03, wid / 2, hgt}));
    }
    case Shape::kFence: {
      Hit h = hit_box(r, {-len / 2, -0.03, hgt - 0.08}, {len / 2, 0.03, hgt});
      h = nearer(h, hit_box(r, {-len / 2, -0.03, 0.25}, {len / 2, 0.03, 0.33}));
      for (double x = -len / 2; x <= len / 2 + 1e-9; x += 2.5) {
        h = nearer(h, hit_cylinder(r, x, 0, 0.05, 0, hgt));
      }
      return h;
    }
  }
  return {};
}

WorldHit World::cast(const Ray& ray, double t, const std::vector<std::uint32_t>& candidates,
                     PoseCache& cache) const {
  if (cache.t != t || cache.pose.size() != actors_.size()) {
    cache.t = t;
    cache.pose.resize(actors_.size());
    cache.valid.assign(actors_.size(), 0);
  }
  WorldHit best;
  const Hit g = hit_ground(ray);
  if (g.t < kNoHit) {
    best.t = g.t;
    best.normal = g.normal;
    best.reflectivity =
        0.2;  // asphalt and concrete (0.12 before the intensity fit; docs/simulator.md)
    best.actor = -1;
  }
  for (std::uint32_t i : candidates) {
    if (!cache.valid[i]) {
      cache.pose[i] = actor_pose(i, t);
      cache.valid[i] = 1;
    }
    const Pose& p = cache.pose[i];
    // Early outs: farther than what is already hit, then the actor's box (every shape lies in
    // its truth box; the margin covers fence posts and rounding).
    if (best.t < kNoHit) {
      const double dx = p.x - ray.origin.x, dy = p.y - ray.origin.y, reach = best.t + radius_[i];
      if (dx * dx + dy * dy > reach * reach) continue;
    }
    const Ray local{p.to_local(ray.origin), p.rotate_to_local(ray.direction)};
    const Actor& a = actors_[i];
    constexpr double kMargin = 0.15;
    const Hit bound = hit_box(local, {-a.size.x / 2 - kMargin, -a.size.y / 2 - kMargin, -kMargin},
                              {a.size.x / 2 + kMargin, a.size.y / 2 + kMargin, a.size.z + kMargin});
    if (bound.t >= best.t) {
      // Missed, or behind what is already hit; a ray starting inside the box still counts.
      const V3 o = local.origin;
      const bool inside = std::abs(o.x) <= a.size.x / 2 + kMargin &&
                          std::abs(o.y) <= a.size.y / 2 + kMargin && o.z >= -kMargin &&
                          o.z <= a.size.z + kMargin;
      if (!inside) continue;
    }
    bool translucent = false;
    const Hit h = hit_actor_local(a, local, t, translucent);
    if (h.t < best.t) {
      best.t = h.t;
      best.normal = p.rotate_to_world(h.normal);
      best.reflectivity = a.reflectivity;
      best.actor = static_cast<std::int64_t>(i);
      best.translucent = translucent;
    }
  }
  return best;
}

}  // namespace stac::sim
