#pragma once
// Speed and separation toward obstacles (ISO/TS 15066's SSM, as closing_speed.hpp is for the
// person; Nav2's collision monitor's "approach" model): the controller's last stage before the
// acceleration limits, so that nothing upstream -- the plan, the barrier's repair pushing away
// from the person, the closing-speed limit -- drives the footprint into an obstacle it could not
// stop short of.
//   The command u (vx, vy, wz) held for the reaction time t_r, then braked to a stop with every
//   component in proportion (the same arc, the fastest footprint point decelerating at a_r),
//   sweeps the footprint along one arc. The command is scaled to k u, 0 <= k <= 1, the largest
//   whose sweep, plus margin_m more of the fastest point's travel, covers no obstacle cell:
//   with d the fastest point's travel along the arc to the first pose that would cover one,
//   k |u|_fp t_r + (k |u|_fp)^2 / (2 a_r) = d - margin_m  (|u|_fp: the fastest point's speed).
// Along a wall, and away from an obstacle, the sweep covers nothing: the command is left alone;
// toward one it is slowed to what stops short of it, and the arc (direction, turning) is kept.
// The arc is checked at poses sweep_step_m of travel apart with the footprint grown by half a
// step, so no contact between two poses is missed (the limit is that much more cautious); cells
// that grown footprint already covers are not counted (a robot touching an obstacle may leave).
// Where an obstacle first appears inside the stopping distance, the acceleration limits after
// this stage keep the command from dropping faster than the base can brake.
// Why it exists: in the dead-end corridors the barrier's repair and the plan's sidestep round a
// person walking back at the robot drove it into the corridor's wall (docs/eval/SESSIONS.md,
// thirty-third session). Obstacles are the costmap's cells that have held an obstacle for at
// least `settled_s` (Costmap::obstacle_age_s): walls, furniture, a person standing. A walking
// pedestrian's cells are younger (they leave each within a fraction of a second): taken as
// standing, the limit slowed the robot in their way until they walked into it (crowds, same
// section); the plan's collision cost and the supervisor keep them. The followed person is
// masked out of the costmap (closing_speed.hpp is theirs). What a cost: a wall that comes into
// view within reach (round a corner) is not limited for its first `settled_s`.
#include <vector>

#include "core/control/closing_speed.hpp"
#include "core/control/dcbf_repair.hpp"
#include "core/geometry/pose2.hpp"
#include "core/perception/costmap.hpp"

namespace core {

struct ObstacleSpeedConfig {
  double robot_decel_mps2 = 0;    // a_r; 0 = off
  double reaction_time_s = 0.05;  // t_r: command latency and the control period
  double margin_m = 0.05;         // the fastest point's travel left before a stop would touch
  double settled_s = 1.0;         // an obstacle cell counts once it has been occupied this long
  double sweep_step_m = 0.02;     // the fastest point's travel between the poses checked
  Footprint footprint;
};

struct ObstacleSpeedResult {
  Twist u;
  bool limited = false;           // the command was scaled down
  double scale = 1.0;             // k
  double free_travel_m = 1e9;     // d: the fastest point's travel before the sweep would touch
  int obstacle_cells_looked = 0;  // obstacle cells within reach of the command
};

// The largest speed that stops, after the reaction time, `margin_m` short of `travel_m` (>= 0).
double max_approach_speed_mps(double travel_m, const ObstacleSpeedConfig& c);

// The pose (in the frame of the start) after `u` held for `time_s`: the exact arc.
Pose2 pose_after(const Twist& u, double time_s);

// The fastest any point of `f` moves under `u` (m/s).
double fastest_point_mps(const Twist& u, const Footprint& f);

class ObstacleSpeedLimit {
 public:
  ObstacleSpeedLimit() = default;
  explicit ObstacleSpeedLimit(const ObstacleSpeedConfig& config) : config_(config) {}
  [[nodiscard]] const ObstacleSpeedConfig& config() const { return config_; }

  // `robot` in odom (the costmap's frame), `u` in base_link. Allocates only while the number of
  // obstacle cells in reach grows past what it has seen.
  ObstacleSpeedResult apply(const Costmap& costmap, const Pose2& robot, const Twist& u);

 private:
  ObstacleSpeedConfig config_;
  std::vector<Point2> cells_;  // obstacle cells in reach, base_link (reused)
};

}  // namespace core
