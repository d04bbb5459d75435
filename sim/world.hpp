// The simulated world: ground with gentle slopes and curbs, static clutter and moving actors
// (cars, pedestrians, bicyclists), each a few primitives in its own frame, intersected at the
// exact time of every ray. Deterministic: nothing here draws random numbers.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "sim/geometry.hpp"

namespace stac::sim {

enum class ObjectClass : std::uint8_t {
  kCar,
  kPedestrian,
  kBicyclist,
  // Background kinds: everything that is none of the three.
  kBuilding,
  kWall,
  kFence,
  kTree,
  kBush,
  kPole,
  kSign,
  kBin,
  kClutter,
};
std::string_view class_name(ObjectClass c) noexcept;
// The kind named `name` (class_name's inverse); false when none is.
bool class_from_name(std::string_view name, ObjectClass& out) noexcept;
bool is_foreground(ObjectClass c) noexcept;  // car, pedestrian or bicyclist

enum class Shape : std::uint8_t {
  kBox,  // one box: buildings, walls, bins, clutter
  kSedan,
  kVan,
  kTruck,   // vehicles (truck with trailer: a longer truck)
  kWalker,  // pedestrian, limbs swinging while moving
  kWalkerWithBike,
  kWalkerWithSuitcase,
  kCyclist,  // bicycle and pedalling rider
  kTree,
  kBush,
  kPole,
  kSign,
  kFence,
};

// Where an actor is over time: waypoints (x, y, t) followed linearly; before the first and
// after the last it stands still. Heading follows the direction of travel (kept while stopped).
struct Trajectory {
  struct Waypoint {
    double x, y, t;
  };
  std::vector<Waypoint> points;
  double fixed_yaw = 0.0;  // heading for static actors (a single waypoint)

  Pose pose_at(double t) const;  // z = 0 (the world adds the ground height)
  V3 velocity_at(double t) const;
};

struct Actor {
  std::uint32_t id = 0;
  ObjectClass cls = ObjectClass::kClutter;
  Shape shape = Shape::kBox;
  V3 size;                    // truth box: length (x), width (y), height (z), m
  double reflectivity = 0.3;  // 0..1, diffuse
  double phase = 0.0;         // gait / pedalling phase offset
  Trajectory path;
};

struct GroundConfig {
  double slope_x = 0.01;  // rise per metre along x
  double slope_y = -0.005;
  double wave_amplitude = 0.3;  // m, a long gentle undulation along x
  double wave_length = 120.0;   // m
  // Raised sidewalks beside a road along x: |y - road_y| in [road_half_width, outer].
  double road_y = 0.0;
  double road_half_width = 7.0;
  double sidewalk_width = 3.5;
  double curb_height = 0.15;
  bool has_road = true;
  double cross_road_x = 1e9;  // a crossing road along y at this x (no sidewalk there)
  double cross_half_width = 7.0;
};

struct WorldHit {
  double t = kNoHit;
  V3 normal;
  double reflectivity = 0.0;
  std::int64_t actor = -1;   // index into actors, -1 = ground
  bool translucent = false;  // vegetation: a beam may pass through
};

class World {
 public:
  World(GroundConfig ground, std::vector<Actor> actors);

  const std::vector<Actor>& actors() const noexcept { return actors_; }
  const GroundConfig& ground() const noexcept { return ground_; }
  double ground_height(double x, double y) const noexcept;   // road surface or sidewalk top
  double terrain_height(double x, double y) const noexcept;  // without curbs

  // Poses of actors at one instant, computed on first use (one per firing of the sensor: the
  // 64 beams of a firing leave within 45 us, in which an actor moves at most 1.6 mm).
  struct PoseCache {
    double t = -1.0;
    std::vector<Pose> pose;
    std::vector<std::uint8_t> valid;
  };

  // Nearest surface along `ray` at time t, among the ground and the actors listed in
  // `candidates` (indices into actors()).
  WorldHit cast(const Ray& ray, double t, const std::vector<std::uint32_t>& candidates,
                PoseCache& cache) const;
  // Pose of actor i at time t, with z on the ground and its trigonometry.
  Pose actor_pose(std::size_t i, double t) const;
  // Radius of a circle around the actor's origin containing all of it (m).
  double actor_radius(std::size_t i) const noexcept;

 private:
  Hit hit_ground(const Ray& ray) const;
  Hit hit_actor_local(const Actor& a, const Ray& local, double t, bool& translucent) const;

  GroundConfig ground_;
  std::vector<Actor> actors_;
  std::vector<double> radius_;
};

}  // namespace stac::sim
