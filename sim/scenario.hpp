// Scenarios: a world and an ego drive built deterministically from a name and a seed.
//   urban         busy street with an intersection, the ego driving and stopping
//   intersection  the ego parked at a corner, heavy traffic in all directions
//   highway       three lanes each way, fast cars and trucks, barriers
//   parking-lot   rows of parked cars, slow cars and walkers between them
//   crowd         a street full of pedestrians (stress), the ego creeping
//   empty         the urban street without cars, pedestrians or bicyclists (background set)
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "rt/expected.hpp"
#include "sim/lidar.hpp"
#include "sim/world.hpp"

namespace stac::sim {

struct Scenario {
  std::string name;
  GroundConfig ground;
  std::vector<Actor> actors;
  Trajectory ego_path;
};

// The ego's footprint in plan (m), centred on the ego origin (the sensor's x, y): the same
// box the scenarios keep every actor out of and the ego body the sensor sees (LidarConfig::body).
inline constexpr double kEgoLength = 4.6, kEgoWidth = 1.9;

// Traffic is physically consistent with the ego: when a scenario is built, every car,
// pedestrian and bicyclist is checked every 0.05 s of the drive against the ego's footprint and
// against every other road user accepted before it, with 0.3 m of clearance along and 0.05 m
// across. An actor in the way waits (pauses on its path, repeatedly, as long as needed: it
// yields, queues behind the ego, lets it pass); one that cannot be cleared by waiting (standing
// in the ego's way, started inside another) is left out. Every path is driven with bounded
// acceleration (cars 2.5 m/s^2, bicyclists 1.5, pedestrians 1.0): stops are braked into.

const std::vector<std::string>& scenario_names();
rt::Result<Scenario> make_scenario(const std::string& name, std::uint64_t seed, double duration_s);

// The ego's full state at time t on the scenario's ground (attitude from the terrain slope).
EgoState ego_state(const World& world, const Trajectory& path, double t);

}  // namespace stac::sim
