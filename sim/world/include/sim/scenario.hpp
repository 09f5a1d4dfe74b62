#pragma once
// What a simulated run contains: the fixed world, the person's walk, the pedestrians (social
// force) and replayed recorded people, where the robot starts, and how long it lasts. Built-in
// scenarios follow the paper's section VI (reference/evaluation.md); each is selectable by name.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "sim/social_force.hpp"
#include "sim/static_world.hpp"
#include "sim/trajectory.hpp"

namespace sim {

struct Scenario {
  std::string name;
  std::string description;
  StaticWorld world;
  Trajectory person;  // the followed person (world frame)
  double person_radius_m = 0.25;
  core::Pose2 robot_start;  // world frame
  std::vector<Pedestrian> pedestrians;
  std::vector<Trajectory> replayed;  // recorded people: move as recorded, avoid no one
  double duration_s = 60.0;
};

// Every built-in person starts walking at this time (s), after the daemon armed (costmap,
// tracker, base); a recorded person appears then.
inline constexpr double kBuiltInStartDelayS = 4.0;
// Every built-in person speeds up from standing and slows down to standing this evenly (m/s^2;
// a brisk start and stop, the acceleration the corners and the daemon's closing-speed rule
// assume), not from 0 to walking speed in one 50 ms sample: a start no robot behind could follow
// without an error, which up to the twenty-third session was most of e_y and e_theta in the
// straight walks (docs/EVALUATION.md). The dead ends keep 1 m/s^2 (their turn back).
inline constexpr double kBuiltInStartStopAccelMps2 = 3.0;

struct ScenarioInfo {
  const char* name;
  const char* description;
};
// The built-in scenarios, in the reference's order.
const std::vector<ScenarioInfo>& builtin_scenarios();
// A built-in scenario by name (seeded where it has randomness); nullopt for an unknown name.
std::optional<Scenario> make_scenario(const std::string& name, uint32_t seed = 1);

// Options for the seeded random benchmark (scenario 7 and the crowd and speed variants).
struct RandomScenarioOptions {
  int pedestrians = 10;
  int obstacles = 8;
  double speed_min_mps = 0.7;
  double speed_max_mps = 1.5;
  double duration_s = 60.0;
  // The person starts and stops this evenly; 0: at once, the walks up to the twenty-third
  // session (a test can keep a situation found on one of them).
  double start_stop_accel_mps2 = kBuiltInStartStopAccelMps2;
  // > 0: obstacles also beside the walk, every 2-4 m of it, on one side or both (a passage),
  // their surfaces this far from the person's path (to 0.3 m more): the constrained worlds.
  // Below ~1.45 m they close the points beside the person (b = 0.7 m, then the costmap's
  // inflation up to R); near 0.8 m the point behind at corners. They come on top of the
  // seed's world, which stays as it is (walk, obstacles, pedestrians), so cases pair by seed.
  double beside_walk_clearance_m = 0;
  // The person's turns at the legs' ends: up to +-max_turn_rad (one uniform draw scaled to it,
  // so a smaller bound scales the same seed's turns down), walked on arcs no faster than
  // corner_turn_rate_radps; bounds below 90 degrees walk 2-4 m legs and are pulled toward the
  // middle, so that they turn round before the edge. The benchmark's walks: +-100 deg at 3 rad/s;
  // the recorded pedestrians of sim/data/pedestrians turn far less (docs/eval/SESSIONS.md,
  // thirty-seventh session: companion-eval's `turns-D` cases).
  double max_turn_rad = 1.75;
  double corner_turn_rate_radps = 3.0;
};
Scenario random_scenario(uint32_t seed, const RandomScenarioOptions& options);

// Recorded pedestrians: the person `follow_id` of `dataset` is followed (from their first to
// their last observation), everyone else is replayed around them; the robot starts 1 m behind.
// Everyone walks smoothly between their observations (smooth_track), as the recorded people did.
struct PedestrianDataset;
std::optional<Scenario> recorded_scenario(const PedestrianDataset& dataset, int follow_id,
                                          std::string* error);

}  // namespace sim
