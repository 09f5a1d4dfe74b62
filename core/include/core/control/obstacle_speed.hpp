#pragma once
// Speed and separation toward obstacles (after PX4's collision prevention and ISO/TS 15066's
// SSM, as closing_speed.hpp does for the person): the last stage before the acceleration limits,
// so that nothing upstream -- the plan, the barrier's repair pushing away from the person, the
// closing-speed limit -- drives the footprint into an obstacle faster than it can stop.
//   for every obstacle cell o of the costmap near the robot (base_link):
//   gap D: the distance from the footprint (a box) to o's centre, less `margin_m`;
//   n: the unit direction from the footprint's nearest point r to o;
//   v_o: that point's velocity toward o, n . (v + w x r), linear in the command (vx, vy, wz);
//   limit: v_o t_r + v_o^2 / (2 a_r) <= D (reaction, then braking at a_r), i.e.
//          v_o <= a_r (sqrt(t_r^2 + 2 D / a_r) - t_r).
// Every limit is >= 0, so standing still meets them all and motion away from an obstacle is
// never limited: a robot already at an obstacle may leave it. Each component of the command is
// only ever reduced toward zero (no motion is added, not even away from the wall: the person's
// limits upstream must keep holding). The command is moved onto the limits it breaks one at a
// time and back within [0, u] (a few sweeps: it keeps the motion along a wall, where scaling
// would stop it), then scaled toward zero until every limit holds exactly. Why it exists: in the
// dead-end corridors the barrier's repair and the plan's sidestep round a person walking back at
// the robot drove it into the corridor's wall (docs/EVALUATION.md, thirty-third session). Obstacles
// are what the lidar sees, pedestrians included (as if they stood still); the followed person is
// masked out of the costmap (closing_speed.hpp is theirs).
#include <array>
#include <vector>

#include "core/control/closing_speed.hpp"
#include "core/control/dcbf_repair.hpp"
#include "core/geometry/pose2.hpp"
#include "core/perception/costmap.hpp"

namespace core {

struct ObstacleSpeedConfig {
  double robot_decel_mps2 = 0;    // a_r; 0 = off
  double reaction_time_s = 0.05;  // t_r: command latency and the control period
  double margin_m = 0.05;         // gap left between the footprint and an obstacle cell's centre
  Footprint footprint;
};

struct ObstacleSpeedResult {
  Twist u;
  bool limited = false;           // the command was changed
  double nearest_gap_m = 1e9;     // footprint to the nearest obstacle cell looked at
  int obstacle_cells_looked = 0;  // obstacle cells within reach of the command
};

// The largest speed toward an obstacle `gap_m` away that still stops `margin_m` short of it.
double max_approach_speed_mps(double gap_m, const ObstacleSpeedConfig& c);

class ObstacleSpeedLimit {
 public:
  // One obstacle cell's limit on the command: a . (vx, vy, wz) <= s.
  struct Limit {
    std::array<double, 3> a;
    double s;
  };

  ObstacleSpeedLimit() = default;
  explicit ObstacleSpeedLimit(const ObstacleSpeedConfig& config) : config_(config) {}
  [[nodiscard]] const ObstacleSpeedConfig& config() const { return config_; }

  // `robot` in odom (the costmap's frame), `u` in base_link. Allocates only while the number of
  // obstacle cells in reach grows past what it has seen.
  ObstacleSpeedResult apply(const Costmap& costmap, const Pose2& robot, const Twist& u);

 private:
  ObstacleSpeedConfig config_;
  std::vector<Limit> limits_;  // reused
};

}  // namespace core
