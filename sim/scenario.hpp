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

const std::vector<std::string>& scenario_names();
rt::Result<Scenario> make_scenario(const std::string& name, std::uint64_t seed, double duration_s);

// The ego's full state at time t on the scenario's ground (attitude from the terrain slope).
EgoState ego_state(const World& world, const Trajectory& path, double t);

}  // namespace stac::sim
