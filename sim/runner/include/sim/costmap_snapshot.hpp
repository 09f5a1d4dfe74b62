#pragma once
// The daemon's costmap at one moment, as a ROS map_server map (an 8-bit PGM and its YAML:
// `image`, `resolution`, `origin`, `negate`, `occupied_thresh`, `free_thresh`), so any map viewer
// opens it, plus what the daemon knew then (robot, person, q^d in odom; the controller's best
// plan's cost by term, the obstacle ages' image) as extra YAML keys. `companion-eval
// --costmap-at` writes them; sim/eval/plot_costmap.py draws one.
#include <string>
#include <vector>

#include "core/geometry/pose2.hpp"
#include "core/perception/costmap.hpp"

namespace sim {

struct CostmapMarks {
  double t_s = 0;
  core::Pose2 robot_odom;
  bool has_person = false;
  core::Pose2 person_odom;
  bool has_goal = false;
  core::Pose2 goal_odom;
  bool tracking = false;  // the controller ran on q^d: the plan_* costs hold
  double plan_tracking = 0, plan_collision = 0, plan_barrier = 0;
  double cost_threshold = 30;  // R
  // The person's predicted path as the controller sees it (the tracker's constant-velocity,
  // constant-yaw-rate prediction) and q^d carried along it, every second of the horizon.
  std::vector<core::Pose2> predicted_person;
  std::vector<core::Pose2> predicted_goal;
  // The obstacle layer's ages (costmap_age_pgm) beside the map, and the age from which the speed
  // limit toward obstacles counts a cell (obstacle_speed.settled_s); no key when empty.
  std::string age_image;
  double obstacle_settled_s = 0;
};

// Binary PGM (P5), one pixel a cell, the top row the largest y (as map_server reads it): cost 0
// white (255), 100 black (0), linear between.
std::string costmap_pgm(const core::Costmap& map);
// The obstacle cells' ages in the same layout: white (255) where there is no obstacle, else
// 254 - the age in Costmap::kObstacleAgeStepS steps (a new obstacle 254, 12.7 s or older 0), so
// a viewer shows old, settled obstacles dark and a walker's fresh cells nearly white.
std::string costmap_age_pgm(const core::Costmap& map);
// The map_server YAML for `image_name`, with the marks.
std::string costmap_yaml(const core::Costmap& map, const std::string& image_name,
                         const CostmapMarks& marks);

}  // namespace sim
