#include "sim/scenario.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <unordered_map>

namespace stac::sim {
namespace {

// A small deterministic generator (splitmix64): the same seed gives the same world on every
// machine, independent of the standard library's distributions.
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : state_(seed * 0x9E3779B97F4A7C15ULL + 0x1234567ULL) {}
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }
  double uniform(double lo, double hi) {
    return lo + (hi - lo) * static_cast<double>(next() >> 11) * 0x1.0p-53;
  }
  bool chance(double p) { return uniform(0, 1) < p; }
  int integer(int lo, int hi) {
    return lo + static_cast<int>(next() % static_cast<std::uint64_t>(hi - lo + 1));
  }

 private:
  std::uint64_t state_;
};

// A box in plan: centre, heading (cos, sin) and half extents, m.
struct Footprint {
  double x, y, c, s, hl, hw;
  double radius() const { return std::hypot(hl, hw); }
};

Footprint footprint_at(const Trajectory& path, double length, double width, double t) {
  const Pose p = path.pose_at(t);
  return {p.x, p.y, std::cos(p.yaw), std::sin(p.yaw), length / 2, width / 2};
}

// Separating axes of two rectangles.
bool overlaps(const Footprint& a, const Footprint& b) {
  const double dx = b.x - a.x, dy = b.y - a.y, reach = a.radius() + b.radius();
  if (dx * dx + dy * dy > reach * reach) return false;
  auto separated = [&](double ux, double uy) {
    const double pa = a.hl * std::abs(a.c * ux + a.s * uy) + a.hw * std::abs(-a.s * ux + a.c * uy);
    const double pb = b.hl * std::abs(b.c * ux + b.s * uy) + b.hw * std::abs(-b.s * ux + b.c * uy);
    return std::abs(dx * ux + dy * uy) > pa + pb;
  };
  return !(separated(a.c, a.s) || separated(-a.s, a.c) || separated(b.c, b.s) ||
           separated(-b.s, b.c));
}

struct Aabb {
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  void add(const Footprint& f) {
    const double r = f.radius();
    x0 = std::min(x0, f.x - r);
    y0 = std::min(y0, f.y - r);
    x1 = std::max(x1, f.x + r);
    y1 = std::max(y1, f.y + r);
  }
  bool meets(const Aabb& o) const { return x0 <= o.x1 && o.x0 <= x1 && y0 <= o.y1 && o.y0 <= y1; }
};

// A pause on a path: at the path's own time `at` (s, before any pause) it stands `wait` s.
struct Pause {
  double at, wait;
};

// A path as driven: the trajectory, the path's own time at each of its waypoints, and per pause
// (in order) the drive's times when it comes to a stand and when it moves off again.
struct TimedPath {
  Trajectory path;
  std::vector<double> own;
  std::vector<std::pair<double, double>> stands;
  // The path's own time at drive time t.
  double own_at(double t) const {
    const auto& p = path.points;
    if (p.empty()) return t;
    if (t <= p.front().t) return own.front();
    for (std::size_t i = 1; i < p.size(); ++i) {
      if (t <= p[i].t) {
        const double dt = p[i].t - p[i - 1].t;
        return dt <= 0 ? own[i] : own[i - 1] + (own[i] - own[i - 1]) * (t - p[i - 1].t) / dt;
      }
    }
    return own.back() + (t - p.back().t);
  }
};

// `path` with the pauses (sorted, disjoint) inserted, then driven with its speed changing at
// most at `accel` m/s^2: every stop is braked into and pulled away from, a stop soon after the
// start or after another is reached more slowly (the speed at each waypoint is bounded by a
// backward and a forward pass, then each straight piece between waypoints is driven as
// accelerate - cruise - brake, sampled every 0.05 s while the speed changes). Nothing on a path
// stops dead from speed; a feasible path keeps its timing.
TimedPath with_pauses(const Trajectory& path, const std::vector<Pause>& pauses, double accel) {
  TimedPath out;
  out.path.fixed_yaw = path.fixed_yaw;
  if (path.points.size() < 2) {
    out.path = path;
    for (const auto& w : path.points) out.own.push_back(w.t);
    return out;
  }
  // 1. The pauses as instant stops (x, y, t; own time).
  std::vector<Trajectory::Waypoint> in;
  std::vector<double> own;
  double shift = 0.0;
  std::size_t k = 0;
  for (const Trajectory::Waypoint& w : path.points) {
    while (k < pauses.size() && pauses[k].at < w.t) {
      const Pose p = path.pose_at(pauses[k].at);
      if (pauses[k].at > path.points.front().t) {
        in.push_back({p.x, p.y, pauses[k].at + shift});
        own.push_back(pauses[k].at);
      }
      shift += pauses[k].wait;
      in.push_back({p.x, p.y, pauses[k].at + shift});
      own.push_back(pauses[k].at);
      ++k;
    }
    in.push_back({w.x, w.y, w.t + shift});
    own.push_back(w.t);
  }
  // (A waypoint at the previous one's place and time adds nothing: dropped.)
  std::size_t kept = 1;
  for (std::size_t i = 1; i < in.size(); ++i) {
    const auto& q = in[kept - 1];
    if (in[i].t - q.t < 1e-9 && std::hypot(in[i].x - q.x, in[i].y - q.y) < 1e-9) continue;
    in[kept] = in[i];
    own[kept++] = own[i];
  }
  in.resize(kept);
  own.resize(kept);
  if (kept < 2) {
    out.path.points = in;
    out.own = own;
    return out;
  }
  // 2. Speeds at the waypoints: 0 next to a stand, else the lower of the two pieces'; then
  // bounded by what braking (backward) and accelerating (forward) over each piece allow.
  const std::size_t n = in.size();
  std::vector<double> len(n - 1), speed(n - 1), u(n);
  std::vector<bool> stand(n - 1);
  for (std::size_t i = 0; i + 1 < n; ++i) {
    len[i] = std::hypot(in[i + 1].x - in[i].x, in[i + 1].y - in[i].y);
    const double dt = in[i + 1].t - in[i].t;
    stand[i] = len[i] < 1e-9;
    speed[i] = stand[i] || dt <= 0 ? 0.0 : len[i] / dt;
  }
  for (std::size_t j = 0; j < n; ++j) {
    const bool left = j > 0, right = j + 1 < n;
    if ((left && stand[j - 1]) || (right && stand[j])) {
      u[j] = 0.0;
    } else {
      u[j] = std::min(left ? speed[j - 1] : speed[j], right ? speed[j] : speed[j - 1]);
    }
  }
  for (std::size_t i = n - 1; i-- > 0;) {
    if (!stand[i]) u[i] = std::min(u[i], std::sqrt(u[i + 1] * u[i + 1] + 2 * accel * len[i]));
  }
  for (std::size_t i = 0; i + 1 < n; ++i) {
    if (!stand[i]) u[i + 1] = std::min(u[i + 1], std::sqrt(u[i] * u[i] + 2 * accel * len[i]));
  }
  // 3. Each piece driven: a stand keeps its duration; a moving piece accelerates from u[i],
  // cruises at most at its own speed and brakes to u[i + 1].
  double t = in.front().t;
  out.path.points.push_back(in.front());
  out.own.push_back(own.front());
  auto emit = [&](std::size_t i, double d, double at) {
    const double f = len[i] > 0 ? d / len[i] : 1.0;
    out.path.points.push_back(
        {in[i].x + (in[i + 1].x - in[i].x) * f, in[i].y + (in[i + 1].y - in[i].y) * f, at});
    out.own.push_back(own[i] + (own[i + 1] - own[i]) * f);
  };
  for (std::size_t i = 0; i + 1 < n; ++i) {
    if (stand[i]) {
      const double dt = in[i + 1].t - in[i].t;
      if (dt <= 0) continue;
      out.stands.push_back({t, t + dt});
      t += dt;
      out.path.points.push_back({in[i + 1].x, in[i + 1].y, t});
      out.own.push_back(own[i + 1]);
      continue;
    }
    const double u0 = u[i], u1 = u[i + 1], v = speed[i];
    if (v <= 0) {  // no time to cover it (not made by the builders): kept as it is
      out.path.points.push_back({in[i + 1].x, in[i + 1].y, t});
      out.own.push_back(own[i + 1]);
      continue;
    }
    const double peak = std::min(v, std::sqrt(0.5 * (2 * accel * len[i] + u0 * u0 + u1 * u1)));
    const double d_up = (peak * peak - u0 * u0) / (2 * accel),
                 d_down = (peak * peak - u1 * u1) / (2 * accel);
    // (Phases shorter than a microsecond are rounding: none.)
    const double t_up = peak - u0 > 1e-6 ? (peak - u0) / accel : 0.0;
    const double t_down = peak - u1 > 1e-6 ? (peak - u1) / accel : 0.0;
    const double d_cruise = std::max(0.0, len[i] - d_up - d_down);
    const int n_up = static_cast<int>(std::ceil(t_up / 0.05)),
              n_down = static_cast<int>(std::ceil(t_down / 0.05));
    for (int q = 1; q <= n_up; ++q) {
      const double tau = t_up * q / n_up;
      emit(i, u0 * tau + 0.5 * accel * tau * tau, t + tau);
    }
    t += t_up;
    if (d_cruise > 1e-6) {  // (shorter: rounding)
      t += d_cruise / peak;
      emit(i, d_up + d_cruise, t);
    }
    for (int q = 1; q <= n_down; ++q) {
      const double tau = t_down * q / n_down;
      emit(i, std::min(len[i], d_up + d_cruise + peak * tau - 0.5 * accel * tau * tau), t + tau);
    }
    t += t_down;
  }
  return out;
}

// Speed ramps (m/s^2): cars brake and pull away firmly, bicyclists and pedestrians gently.
double ramp_accel(ObjectClass c) {
  return c == ObjectClass::kCar ? 2.5 : c == ObjectClass::kBicyclist ? 1.5 : 1.0;
}

class Builder {
 public:
  Builder(Scenario& s, std::uint64_t seed, double duration)
      : s_(s), rng_(seed), horizon_(std::max(duration, 0.0) + 0.1) {}
  Rng& rng() { return rng_; }

  // The ego's path: set before any actor is added (actors are checked against it).
  void set_ego(Trajectory path) {
    s_.ego_path = std::move(path);
    const std::size_t n = samples();
    ego_.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      ego_[i] = footprint_at(s_.ego_path, kEgoLength, kEgoWidth, static_cast<double>(i) * kStep);
    }
    ego_windows_ = windows_of(ego_);
  }

  // Checks the last added actor against the ego and the road users accepted so far and makes it
  // wait where it is in the way; leaves it out (returns false) when waiting does not clear it.
  bool commit() {
    if (!pending_) return true;
    pending_ = false;
    const std::size_t i = s_.actors.size() - 1;
    Actor& a = s_.actors[i];
    if (!is_foreground(a.cls)) return accept(i, {});
    const Trajectory original = a.path;
    const bool moving = original.points.size() > 1;
    std::vector<Pause> pauses = std::move(stops_);
    stops_.clear();
    const double accel = ramp_accel(a.cls);
    for (int attempt = 0; attempt < 200; ++attempt) {
      const TimedPath timed = with_pauses(original, pauses, accel);
      a.path = timed.path;
      std::vector<Footprint> fp(samples());
      for (std::size_t k = 0; k < fp.size(); ++k) {
        fp[k] = footprint_at(a.path, a.size.x + 2 * kClearLong, a.size.y + 2 * kClearSide,
                             static_cast<double>(k) * kStep);
      }
      const double tc = first_conflict(a, fp);
      if (tc < 0) return accept(i, std::move(fp));
      if (!moving || tc <= 0.0) break;
      // Is the conflict while braking for or standing at a pause, or after one?
      int during = -1, before = -1;
      for (std::size_t p = 0; p < pauses.size() && p < timed.stands.size(); ++p) {
        const V3 v = original.velocity_at(pauses[p].at);
        const double braking = std::hypot(v.x, v.y) / accel;
        if (tc < timed.stands[p].first - braking) break;
        if (tc <= timed.stands[p].second) {
          during = static_cast<int>(p);
          break;
        }
        before = static_cast<int>(p);
      }
      if (during >= 0) {  // hit while braking or standing: stop further back
        Pause& p = pauses[static_cast<std::size_t>(during)];
        p.at -= 1.0;
        if (p.at < original.points.front().t - 1e-9 ||
            (during > 0 && p.at <= pauses[static_cast<std::size_t>(during) - 1].at)) {
          break;
        }
        continue;
      }
      const double own = timed.own_at(tc);  // the path's own time at the conflict
      if (before >= 0 && own - pauses[static_cast<std::size_t>(before)].at < 2.0) {
        Pause& p = pauses[static_cast<std::size_t>(before)];  // resumed too early: wait longer
        p.wait = std::max(1.0, 2.0 * p.wait);
      } else {
        pauses.push_back({std::max(original.points.front().t, own - 0.3), 1.0});
      }
    }
    s_.actors.pop_back();
    return false;
  }

  Actor& add(ObjectClass cls, Shape shape, V3 size, double reflectivity) {
    commit();
    pending_ = true;
    stops_.clear();
    Actor a;
    a.id = static_cast<std::uint32_t>(s_.actors.size() + 1);
    a.cls = cls;
    a.shape = shape;
    a.size = size;
    a.reflectivity = reflectivity;
    a.phase = rng_.uniform(0, 2 * std::numbers::pi);
    s_.actors.push_back(a);
    return s_.actors.back();
  }
  Actor& place(ObjectClass cls, Shape shape, V3 size, double refl, double x, double y, double yaw) {
    Actor& a = add(cls, shape, size, refl);
    a.path.points = {{x, y, 0}};
    a.path.fixed_yaw = yaw;
    return a;
  }
  // A vehicle of a random kind: sedan, van, truck (with a trailer now and then).
  Actor& vehicle(double x, double y, double yaw, bool trucks = true) {
    const double u = rng_.uniform(0, trucks ? 1.0 : 0.88);
    const double refl = rng_.uniform(0.15, 0.8);
    if (u < 0.65)
      return place(ObjectClass::kCar, Shape::kSedan,
                   {rng_.uniform(4.1, 4.9), rng_.uniform(1.72, 1.9), rng_.uniform(1.38, 1.55)},
                   refl, x, y, yaw);
    if (u < 0.88)
      return place(ObjectClass::kCar, Shape::kVan,
                   {rng_.uniform(4.9, 5.6), rng_.uniform(1.9, 2.05), rng_.uniform(1.9, 2.4)}, refl,
                   x, y, yaw);
    const double length = rng_.chance(0.3) ? rng_.uniform(13.0, 16.0) : rng_.uniform(7.0, 10.0);
    return place(ObjectClass::kCar, Shape::kTruck,
                 {length, rng_.uniform(2.4, 2.55), rng_.uniform(3.2, 3.9)}, refl, x, y, yaw);
  }
  Actor& pedestrian(double x, double y) {
    const double u = rng_.uniform(0, 1);
    const Shape shape = u < 0.82   ? Shape::kWalker
                        : u < 0.91 ? Shape::kWalkerWithSuitcase
                                   : Shape::kWalkerWithBike;
    const double h = rng_.uniform(1.5, 1.95);
    // Truth boxes hold the swinging limbs (stride 0.39 m), a trailing suitcase, or the bike
    // pushed beside the walker (walker at y = -0.3, bike at y = +0.35).
    const V3 size = shape == Shape::kWalkerWithBike       ? V3{1.85, 1.3, h}
                    : shape == Shape::kWalkerWithSuitcase ? V3{0.95, 0.9, h}
                                                          : V3{0.8, 0.65, h};
    return place(ObjectClass::kPedestrian, shape, size, rng_.uniform(0.15, 0.6), x, y, 0);
  }
  Actor& cyclist(double x, double y) {
    return place(ObjectClass::kBicyclist, Shape::kCyclist, {1.8, 0.7, 1.8}, rng_.uniform(0.2, 0.6),
                 x, y, 0);
  }
  // Moves `a` from (x0, y0) in direction yaw at speed v, with an optional stop of `stop_s`
  // seconds at distance `stop_at` along the way (a pause, braked into when committed).
  void drive(Actor& a, double x0, double y0, double yaw, double v, double duration,
             double stop_at = -1.0, double stop_s = 0.0) {
    const double c = std::cos(yaw), s = std::sin(yaw);
    a.path.points.clear();
    a.path.points.push_back({x0, y0, 0});
    const double dist = v * (duration + 5.0);
    a.path.points.push_back({x0 + c * dist, y0 + s * dist, duration + 5.0});
    if (stop_at > 0 && stop_s > 0) stops_ = {{stop_at / v, stop_s}};  // braked into (commit)
    a.path.fixed_yaw = yaw;
  }
  // A turn: straight to the corner, a quarter circle of radius r, then straight on. The corner
  // is taken at most at the speed of 3 m/s^2 sideways, braked into and pulled away from at the
  // ramp rate of cars (ramp_accel).
  void turn(Actor& a, double x0, double y0, double yaw, double v, double to_corner, double r,
            int dir, double duration) {
    const double accel = ramp_accel(a.cls), v_arc = std::min(v, std::sqrt(3.0 * r));
    a.path.points.clear();
    double x = x0, y = y0, t = 0;
    a.path.points.push_back({x, y, t});
    // A straight piece of length len along `heading`, the speed going linearly (in time) from
    // u0 to u1, sampled every 0.05 s.
    auto straight_piece = [&](double heading, double len, double u0, double u1) {
      if (len <= 0) return;
      const double dur = 2.0 * len / (u0 + u1);
      const int n = u0 == u1 ? 1 : static_cast<int>(std::ceil(dur / 0.05));
      const double c = std::cos(heading), s = std::sin(heading);
      for (int i = 1; i <= n; ++i) {
        const double tau = dur * i / n, d = u0 * tau + (u1 - u0) * tau * tau / (2.0 * dur);
        a.path.points.push_back({x + c * d, y + s * d, t + tau});
      }
      x += c * len;
      y += s * len;
      t += dur;
    };
    const double ramp_len = (v * v - v_arc * v_arc) / (2.0 * accel);
    const double braking = std::min(ramp_len, to_corner);
    const double u_corner = std::sqrt(std::max(v_arc * v_arc, v * v - 2.0 * accel * braking));
    straight_piece(yaw, to_corner - braking, v, v);
    straight_piece(yaw, braking, v, u_corner);
    const double cx = x - dir * std::sin(yaw) * r, cy = y + dir * std::cos(yaw) * r;
    for (int i = 1; i <= 8; ++i) {
      const double ang = yaw - dir * std::numbers::pi / 2 + dir * (std::numbers::pi / 2) * i / 8.0;
      const double px = cx + r * std::cos(ang), py = cy + r * std::sin(ang);
      t += std::hypot(px - x, py - y) / u_corner;
      x = px;
      y = py;
      a.path.points.push_back({x, y, t});
    }
    const double out = yaw + dir * std::numbers::pi / 2;
    straight_piece(out, (v * v - u_corner * u_corner) / (2.0 * accel), u_corner, v);
    const double t_end = std::max(duration + 5.0, t + 1.0), rest = (t_end - t) * v;
    a.path.points.push_back({x + std::cos(out) * rest, y + std::sin(out) * rest, t_end});
    a.path.fixed_yaw = yaw;
  }

  // Buildings, trees, poles, signs, bins, bushes, fences and clutter along a street on x in
  // [x0, x1], sidewalks outside |y| = road_half_width.
  void street_furniture(double x0, double x1, const GroundConfig& g) {
    for (int side : {-1, 1}) {
      const double walk_in = g.road_half_width, walk_out = g.road_half_width + g.sidewalk_width;
      double x = x0;
      while (x < x1) {  // building frontage with gaps
        const double len = rng_.uniform(8, 30), depth = rng_.uniform(8, 20),
                     gap = rng_.uniform(0, 9);
        const double setback = rng_.uniform(0.5, 5.0);
        const double cx = x + len / 2;
        if (std::abs(cx - g.cross_road_x) > g.cross_half_width + g.sidewalk_width + len / 2) {
          const double cy = side * (walk_out + setback + depth / 2);
          place(rng_.chance(0.85) ? ObjectClass::kBuilding : ObjectClass::kWall, Shape::kBox,
                {len, depth, rng_.uniform(4, 18)}, rng_.uniform(0.2, 0.7), cx, cy, 0);
          if (gap > 4 && rng_.chance(0.5)) {  // a fence or bushes in the gap
            if (rng_.chance(0.5)) {
              place(ObjectClass::kFence, Shape::kFence, {gap, 0.06, rng_.uniform(1.0, 1.8)}, 0.3,
                    x + len + gap / 2, side * (walk_out + 0.3), 0);
            } else {
              place(ObjectClass::kBush, Shape::kBush, {gap * 0.8, 1.5, rng_.uniform(0.8, 1.6)},
                    0.25, x + len + gap / 2, side * (walk_out + 1.2), 0);
            }
          }
        }
        x += len + gap;
      }
      for (double px = x0 + rng_.uniform(0, 10); px < x1; px += rng_.uniform(6, 16)) {
        if (std::abs(px - g.cross_road_x) < g.cross_half_width + 1.0) continue;
        const double py = side * (walk_in + rng_.uniform(0.4, 0.9));
        const double u = rng_.uniform(0, 1);
        if (u < 0.35) {
          place(ObjectClass::kTree, Shape::kTree,
                {rng_.uniform(2.5, 5), rng_.uniform(2.5, 5), rng_.uniform(5, 9)}, 0.3, px, py, 0);
        } else if (u < 0.55) {
          place(ObjectClass::kPole, Shape::kPole, {0.22, 0.22, rng_.uniform(5, 9)}, 0.45, px, py,
                0);
        } else if (u < 0.68) {
          place(ObjectClass::kSign, Shape::kSign,
                {0.1, rng_.uniform(0.6, 1.0), rng_.uniform(2.2, 3.2)}, 0.9, px, py, 0);
        } else if (u < 0.8) {
          place(ObjectClass::kBin, Shape::kBox, {0.6, 0.6, rng_.uniform(0.8, 1.2)}, 0.35, px, py,
                rng_.uniform(0, 3));
        } else if (u < 0.9) {
          place(ObjectClass::kClutter, Shape::kBox,
                {rng_.uniform(0.3, 1.5), rng_.uniform(0.3, 1.0), rng_.uniform(0.3, 1.2)},
                rng_.uniform(0.1, 0.6), px, side * (walk_out - 0.5), rng_.uniform(0, 3));
        }
      }
    }
  }

 private:
  static constexpr double kStep = 0.05;      // s between checks
  static constexpr double kWindow = 1.0;     // s per window of the coarse check
  static constexpr double kClearLong = 0.3;  // clearance added to each box, m
  static constexpr double kClearSide = 0.05;
  static constexpr double kCell = 10.0;  // m, grid of standing actors

  std::size_t samples() const { return static_cast<std::size_t>(std::floor(horizon_ / kStep)) + 1; }
  static std::size_t per_window() { return static_cast<std::size_t>(std::lround(kWindow / kStep)); }
  static std::vector<Aabb> windows_of(const std::vector<Footprint>& fp) {
    std::vector<Aabb> w((fp.size() + per_window() - 1) / per_window());
    for (std::size_t k = 0; k < fp.size(); ++k) w[k / per_window()].add(fp[k]);
    return w;
  }
  static std::int64_t cell_key(std::int64_t cx, std::int64_t cy) { return cx * 1'000'003 + cy; }

  // Whether actors a and b must be kept clear of each other: every pair of road users (a
  // faster bicyclist queues behind a slower one in the bike lane).
  static bool must_clear(const Actor& a, const Actor& b) {
    return is_foreground(a.cls) && is_foreground(b.cls);
  }

  // First time (s) actor a, with footprints fp (clearance included), meets the ego or an
  // accepted road user; -1 when never.
  double first_conflict(const Actor& a, const std::vector<Footprint>& fp) const {
    const std::vector<Aabb> win = windows_of(fp);
    std::vector<std::size_t> near;
    for (std::size_t w = 0; w < win.size(); ++w) {
      near.clear();
      for (std::size_t j : moving_) {
        if (must_clear(a, s_.actors[j]) && win_[j][w].meets(win[w])) near.push_back(j);
      }
      const auto cx0 = static_cast<std::int64_t>(std::floor(win[w].x0 / kCell));
      const auto cx1 = static_cast<std::int64_t>(std::floor(win[w].x1 / kCell));
      const auto cy0 = static_cast<std::int64_t>(std::floor(win[w].y0 / kCell));
      const auto cy1 = static_cast<std::int64_t>(std::floor(win[w].y1 / kCell));
      for (std::int64_t cx = cx0; cx <= cx1; ++cx) {
        for (std::int64_t cy = cy0; cy <= cy1; ++cy) {
          const auto it = grid_.find(cell_key(cx, cy));
          if (it == grid_.end()) continue;
          for (std::size_t j : it->second) {
            if (must_clear(a, s_.actors[j]) && std::find(near.begin(), near.end(), j) == near.end())
              near.push_back(j);
          }
        }
      }
      const bool ego_near = ego_windows_[w].meets(win[w]);
      if (!ego_near && near.empty()) continue;
      const std::size_t k1 = std::min(fp.size(), (w + 1) * per_window());
      for (std::size_t k = w * per_window(); k < k1; ++k) {
        if (ego_near && overlaps(fp[k], ego_[k])) return static_cast<double>(k) * kStep;
        for (std::size_t j : near) {
          if (overlaps(fp[k], footprint(j, k))) return static_cast<double>(k) * kStep;
        }
      }
    }
    return -1.0;
  }

  Footprint footprint(std::size_t j, std::size_t k) const {
    const Actor& b = s_.actors[j];
    return footprint_at(b.path, b.size.x, b.size.y, static_cast<double>(k) * kStep);
  }

  bool accept(std::size_t i, std::vector<Footprint> fp) {
    const Actor& a = s_.actors[i];
    if (!is_foreground(a.cls)) return true;
    if (win_.size() < s_.actors.size()) win_.resize(s_.actors.size());
    if (a.path.points.size() > 1) {
      // Stored without the clearance (the one being checked carries it).
      for (std::size_t k = 0; k < fp.size(); ++k) fp[k] = footprint(i, k);
      win_[i] = windows_of(fp);
      moving_.push_back(i);
    } else {
      Aabb box;
      box.add(footprint(i, 0));
      for (auto cx = static_cast<std::int64_t>(std::floor(box.x0 / kCell));
           cx <= static_cast<std::int64_t>(std::floor(box.x1 / kCell)); ++cx) {
        for (auto cy = static_cast<std::int64_t>(std::floor(box.y0 / kCell));
             cy <= static_cast<std::int64_t>(std::floor(box.y1 / kCell)); ++cy) {
          grid_[cell_key(cx, cy)].push_back(i);
        }
      }
    }
    return true;
  }

  Scenario& s_;
  Rng rng_;
  double horizon_;
  bool pending_ = false;
  std::vector<Pause> stops_;  // the pending actor's planned stops (drive)
  std::vector<Footprint> ego_;
  std::vector<Aabb> ego_windows_;
  std::vector<std::vector<Aabb>> win_;  // per accepted moving actor, per window
  std::vector<std::size_t> moving_;
  std::unordered_map<std::int64_t, std::vector<std::size_t>> grid_;
};

// Lanes of the default street (road_half_width 9.5): parking at |y| = 8.2 (cars and vans only),
// a bicycle lane at 6.6, driving lanes at 1.8 and 4.6: a truck in the outer lane, a bicyclist and
// a parked van fit side by side.
constexpr double kRoadHalfWidth = 9.5, kParking = 8.2, kBikeLane = 6.6, kInner = 1.8, kOuter = 4.6;

void traffic(Builder& b, double x0, double x1, double cross_x, double duration, int cars,
             int walkers, int cyclists, const GroundConfig& g) {
  Rng& r = b.rng();
  for (double x = x0 + r.uniform(0, 6); x < x1; x += r.uniform(5.5, 14)) {  // parked cars
    for (int side : {-1, 1}) {
      if (std::abs(x - cross_x) < g.cross_half_width + 6 || !r.chance(0.55)) continue;
      b.vehicle(x, side * kParking, side > 0 ? std::numbers::pi : 0.0, false);
    }
  }
  for (int i = 0; i < cars; ++i) {
    for (int attempt = 0; attempt < 3; ++attempt) {  // a car that cannot fit in is drawn again
      const double u = r.uniform(0, 1);
      const double v = r.uniform(6, 13);
      Actor& car = b.vehicle(0, 0, 0);
      if (u < 0.35) {  // same direction as the ego, stopping at the crossing now and then
        const double start = r.uniform(x0, x1);
        const double lane = r.chance(0.5) ? -kInner : -kOuter;
        const bool stops = start < cross_x && r.chance(0.5);
        const double stop_at = stops ? cross_x - g.cross_half_width - 3 - start : -1,
                     stop_s = r.uniform(2, 6);
        b.drive(car, start, lane, 0.0, v, duration, stop_at, stop_s);
        if (lane == -kInner && !b.commit()) {  // in the ego's way: the outer lane instead
          Actor& other = b.vehicle(0, 0, 0);
          b.drive(other, start, -kOuter, 0.0, v, duration, stop_at, stop_s);
        }
      } else if (u < 0.7) {  // oncoming
        b.drive(car, r.uniform(x0, x1 + 60), r.chance(0.5) ? kInner : kOuter, std::numbers::pi, v,
                duration);
      } else if (u < 0.88) {  // on the crossing road
        const int dir = r.chance(0.5) ? 1 : -1;
        b.drive(car, cross_x + dir * -kInner, -dir * r.uniform(25, 90), dir * std::numbers::pi / 2,
                v, duration);
      } else {  // turning from the main road into the crossing road
        const double start = cross_x - r.uniform(20, 70);
        b.turn(car, start, -kInner, 0.0, r.uniform(5, 8), cross_x - start - 6, 6.0 - kInner + 1.0,
               r.chance(0.5) ? 1 : -1, duration);
      }
      if (b.commit()) break;
    }
  }
  // Sidewalk walkers keep right: those heading +x on one lane of the sidewalk, those heading -x
  // on the other (standing ones anywhere), so nobody walks through an oncoming walker. A group
  // walks in file, each a 0.4-0.8 m gap behind the one before. A faster walker that catches up
  // waits (commit); one that meets a walker it cannot wait out is drawn again (up to 3 times).
  for (int i = 0; i < walkers; ++i) {
    const double v = r.chance(0.2) ? 0.0 : r.uniform(0.9, 1.7);
    const int group = r.chance(0.25) ? r.integer(2, 4) : 1;
    double x = 0, y = 0, yaw = 0, length = 0;
    bool placed = false;
    for (int attempt = 0; attempt < 3 && !placed; ++attempt) {
      const int side = r.chance(0.5) ? 1 : -1;
      const bool east = r.chance(0.5);
      yaw = east ? 0.0 : std::numbers::pi;
      const bool outer = (side < 0) == east;  // on the walker's right
      const double off = v == 0.0 ? r.uniform(1.0, g.sidewalk_width - 0.4)
                                  : (outer ? 2.65 : 1.5) + r.uniform(-0.15, 0.15);
      y = side * (g.road_half_width + off);
      x = r.uniform(x0, x1);
      Actor& p = b.pedestrian(x, y);
      if (v > 0) b.drive(p, x, y, yaw, v, duration);
      length = p.size.x;
      placed = b.commit();
    }
    if (!placed) continue;
    double behind = 0.0;
    for (int k = 1; k < group; ++k) {
      Actor& p = b.pedestrian(0, 0);
      behind += length / 2 + p.size.x / 2 + r.uniform(0.4, 0.8);
      length = p.size.x;
      const double px = x - std::cos(yaw) * behind;
      p.path.points = {{px, y, 0}};
      if (v > 0) b.drive(p, px, y, yaw, v, duration);
      b.commit();
    }
  }
  // Crossing the street at the crosswalks (3 m wide, beside the crossing road on either side):
  // each crossing walker on a line of its own, 1 m from the next, so none walks through another.
  std::array<int, 6> lines = {0, 1, 2, 3, 4, 5};
  for (std::size_t k = lines.size() - 1; k > 0; --k) {
    std::swap(lines[k], lines[static_cast<std::size_t>(r.integer(0, static_cast<int>(k)))]);
  }
  for (int i = 0; i < walkers / 6; ++i) {
    const int dir = r.chance(0.5) ? 1 : -1;
    Actor& p = b.pedestrian(0, 0);
    const int line = lines[static_cast<std::size_t>(i) % lines.size()];
    const int pair = line / 2;  // lines 0 and 1 nearest the crossing, then 2 and 3, ...
    const double x = cross_x + (line % 2 ? -1 : 1) * (g.cross_half_width + 0.5 + pair);
    b.drive(p, x, -dir * (g.road_half_width + 2), dir * std::numbers::pi / 2, r.uniform(1.0, 1.6),
            duration, r.uniform(0.5, 3), r.uniform(0, 8));
  }
  for (int i = 0; i < cyclists; ++i) {
    Actor& c = b.cyclist(0, 0);
    const bool with = r.chance(0.6);
    b.drive(c, r.uniform(x0, x1), with ? -kBikeLane : kBikeLane, with ? 0.0 : std::numbers::pi,
            r.uniform(3.5, 7.5), duration);
  }
}

}  // namespace

const std::vector<std::string>& scenario_names() {
  static const std::vector<std::string> names = {"urban",       "intersection", "highway",
                                                 "parking-lot", "crowd",        "empty"};
  return names;
}

rt::Result<Scenario> make_scenario(const std::string& name, std::uint64_t seed, double duration) {
  Scenario s;
  s.name = name;
  Builder b(s, seed, duration);
  Rng& r = b.rng();
  GroundConfig& g = s.ground;
  g.road_half_width = kRoadHalfWidth;
  g.slope_x = r.uniform(-0.015, 0.015);
  g.slope_y = r.uniform(-0.01, 0.01);
  g.wave_amplitude = r.uniform(0.1, 0.4);
  g.wave_length = r.uniform(80, 200);
  auto straight = [&](double x, double y, double v) {  // the ego along +x at v
    Trajectory t;
    t.points = {{x, y, 0}};
    if (v > 0) t.points.push_back({x + v * (duration + 5), y, duration + 5});
    return t;
  };
  if (name == "urban" || name == "empty") {
    const double v = r.uniform(7, 11);
    const double cross = r.uniform(40, 90);
    g.cross_road_x = cross;
    const double x1 = v * duration + 120;
    // Ego: right inner lane, stopping a few seconds at the crossing, its front 1.5 m before the
    // crosswalk (centred 1.5 m outside the crossing road).
    Trajectory ego;
    ego.points = {{-20, -kInner, 0}};
    const double stop_x = cross - g.cross_half_width - 3.0 - 1.5 - kEgoLength / 2;
    const double t_stop = (stop_x + 20) / v;
    ego.points.push_back({-20 + v * (duration + 5), -kInner, duration + 5});
    if (t_stop < duration) {  // braked into at a car's rate, 3 s standing
      ego = with_pauses(ego, {{t_stop, 3.0}}, ramp_accel(ObjectClass::kCar)).path;
    }
    b.set_ego(ego);
    b.street_furniture(-80, x1, g);
    if (name == "urban")
      traffic(b, -60, x1, cross, duration, 14 + r.integer(0, 8), 24 + r.integer(0, 12),
              4 + r.integer(0, 4), g);
  } else if (name == "intersection") {
    g.cross_road_x = 0.0;
    b.set_ego(straight(-g.cross_half_width - 6, -kInner, 0.0));  // parked at the corner
    b.street_furniture(-120, 120, g);
    traffic(b, -120, 120, 0.0, duration, 40 + r.integer(0, 10), 30 + r.integer(0, 10), 8, g);
    for (int i = 0; i < 16; ++i) {  // extra crossing traffic
      for (int attempt = 0; attempt < 3; ++attempt) {
        Actor& car = b.vehicle(0, 0, 0);
        const int dir = r.chance(0.5) ? 1 : -1;
        b.drive(car, dir * -kInner, -dir * r.uniform(30, 150), dir * std::numbers::pi / 2,
                r.uniform(6, 12), duration);
        if (b.commit()) break;
      }
    }
  } else if (name == "highway") {
    g.road_half_width = 12.0;
    g.sidewalk_width = 2.0;
    const double v = r.uniform(22, 30);
    const double x1 = v * duration + 400;
    b.set_ego(straight(0, -5.4, v));
    for (int side : {-1, 1}) {  // concrete barriers and the occasional sign
      for (double x = -150; x < x1; x += 30) {
        b.place(ObjectClass::kWall, Shape::kBox, {30, 0.5, 0.9}, 0.4, x + 15, side * 12.6, 0);
        if (r.chance(0.08))
          b.place(ObjectClass::kSign, Shape::kSign, {0.1, 2.5, 5}, 0.9, x, side * 13.5, 0);
      }
    }
    for (int i = 0; i < 40; ++i) {
      for (int attempt = 0; attempt < 3; ++attempt) {  // a car that cannot fit in is drawn again
        const bool with = r.chance(0.6);
        int lane = r.integer(0, 2);
        const double start = r.uniform(-150, x1), speed = r.uniform(18, 36);
        Actor& car = b.vehicle(0, 0, 0);
        b.drive(car, start, (lane * 3.6 + 1.8) * (with ? -1 : 1), with ? 0.0 : std::numbers::pi,
                speed, duration);
        if (with && lane == 1 && !b.commit()) {  // in the ego's way: another lane
          lane = r.chance(0.5) ? 0 : 2;
          Actor& other = b.vehicle(0, 0, 0);
          b.drive(other, start, -(lane * 3.6 + 1.8), 0.0, speed, duration);
        }
        if (b.commit()) break;
      }
    }
  } else if (name == "parking-lot") {
    // Rows of cars parked nose-in at |y| = 7.5 and 16.5 (cars and vans), aisles at |y| < 4.7
    // (two lanes, y = -2 and +2) and at |y| = 12.
    g.has_road = false;
    b.set_ego(straight(-45, -2.0, 3.0));
    for (double row : {-16.5, -7.5, 7.5, 16.5}) {
      for (int k = -12; k <= 12; ++k) {
        if (!r.chance(0.7)) continue;
        b.vehicle(k * 2.9, row, row > 0 ? -std::numbers::pi / 2 : std::numbers::pi / 2, false);
      }
      b.place(ObjectClass::kPole, Shape::kPole, {0.3, 0.3, 8}, 0.5, -40, row, 0);
      b.place(ObjectClass::kPole, Shape::kPole, {0.3, 0.3, 8}, 0.5, 40, row, 0);
    }
    b.place(ObjectClass::kBuilding, Shape::kBox, {90, 15, 8}, 0.5, 0, 35, 0);
    const double aisles[] = {-12.0, -2.0, 2.0, 12.0};
    for (int i = 0; i < 5; ++i) {
      Actor& car = b.vehicle(0, 0, 0, false);
      const double y = aisles[r.integer(0, 3)];
      b.drive(car, r.uniform(-40, 40), y,
              y == -2.0       ? 0
              : y == 2.0      ? std::numbers::pi
              : r.chance(0.5) ? 0
                              : std::numbers::pi,
              r.uniform(2, 4), duration);
    }
    for (int i = 0, placed = 0; placed < 18 && i < 60; ++i) {
      Actor& p = b.pedestrian(r.uniform(-35, 35), r.uniform(-20, 20));
      if (r.chance(0.7))
        b.drive(p, p.path.points[0].x, p.path.points[0].y, r.uniform(0, 2 * std::numbers::pi),
                r.uniform(0.8, 1.5), duration);
      if (b.commit()) ++placed;
    }
    for (int i = 0, placed = 0; placed < 2 && i < 10; ++i) {
      Actor& c = b.cyclist(0, 0);
      b.drive(c, r.uniform(-40, 0), r.chance(0.5) ? 12.0 : -12.0, 0, r.uniform(3, 5), duration);
      if (b.commit()) ++placed;
    }
  } else if (name == "crowd") {
    g.cross_road_x = 1e9;
    b.set_ego(straight(-20, 0, 1.0));
    b.street_furniture(-60, 80, g);
    // The bicyclists first: the pedestrians, placed after them, keep clear of them.
    for (int i = 0; i < 6; ++i) {
      Actor& c = b.cyclist(0, 0);
      b.drive(c, r.uniform(-40, 40), r.uniform(-5, 5), r.chance(0.5) ? 0 : std::numbers::pi,
              r.uniform(3, 5), duration);
    }
    for (int i = 0, placed = 0; placed < 150 && i < 600;
         ++i) {  // pedestrians everywhere, no traffic
      Actor& p = b.pedestrian(r.uniform(-40, 60), r.uniform(-11, 11));
      if (r.chance(0.8)) {
        b.drive(p, p.path.points[0].x, p.path.points[0].y, r.uniform(0, 2 * std::numbers::pi),
                r.uniform(0.6, 1.6), duration);
      }
      if (b.commit()) ++placed;
    }
  } else {
    std::string list;
    for (const auto& n : scenario_names()) list += (list.empty() ? "" : ", ") + n;
    return rt::make_error("unknown scenario '" + name + "'; use one of: " + list);
  }
  b.commit();
  return s;
}

EgoState ego_state(const World& world, const Trajectory& path, double t) {
  const Pose p = path.pose_at(t);
  EgoState e;
  e.x = p.x;
  e.y = p.y;
  e.yaw = p.yaw;
  e.z = world.ground_height(p.x, p.y);
  // Attitude from the terrain under a 2.8 m wheelbase and 1.6 m track.
  const double c = std::cos(p.yaw), s = std::sin(p.yaw);
  const double front = world.terrain_height(p.x + 1.4 * c, p.y + 1.4 * s);
  const double back = world.terrain_height(p.x - 1.4 * c, p.y - 1.4 * s);
  const double left = world.terrain_height(p.x - 0.8 * s, p.y + 0.8 * c);
  const double right = world.terrain_height(p.x + 0.8 * s, p.y - 0.8 * c);
  e.pitch = -std::atan2(front - back, 2.8);  // nose up = negative pitch about y (x fwd, z up)
  e.roll = std::atan2(right - left, 1.6);
  const V3 v = path.velocity_at(t);
  e.speed = std::hypot(v.x, v.y);
  const double dt = 0.05;
  double dyaw = path.pose_at(t + dt).yaw - path.pose_at(t - dt).yaw;
  while (dyaw > std::numbers::pi) dyaw -= 2 * std::numbers::pi;
  while (dyaw < -std::numbers::pi) dyaw += 2 * std::numbers::pi;
  e.yaw_rate = dyaw / (2 * dt);
  return e;
}

}  // namespace stac::sim
