#pragma once
// The shortest way from the robot to q^d round the obstacles of the costmap: A* on a coarsened
// copy of it (each planning cell the worst of the costmap cells it covers), 8-connected without
// cutting corners. MPPI follows it with one structured sample (mppi.path_guide) when the robot's
// straight line to q^d, or q^d's own way, runs where the footprint would touch an obstacle: its
// random samples explore a few tenths of a metre about the last plan and the steering law goes
// where q^d goes, so round a cluster of obstacles the plan keeps whichever side it first found,
// the long one too, and past an obstacle the person brushes the law runs into it.
// Not a navigation stack: a path per control step, bounded work (max_expansions), no allocation
// once the costmap's size is known. (Nav2's NavFn and Smac planners are ROS-bound; no Debian
// library plans on a grid in place.)
#include <cstdint>
#include <vector>

#include "core/geometry/pose2.hpp"
#include "core/perception/costmap.hpp"

namespace core {

struct CostmapPathConfig {
  // A move of length l costs l (1 + cost_weight c / 100) for a cell of cost c below
  // unsafe_cost, l (1 + cost_weight + unsafe_penalty) at or above it; cells at or above
  // blocked_cost are not entered, except the goal's and on the way out of them (the robot may
  // stand in an obstacle's core: the map moved, or it was pushed), at blocked_penalty more a
  // metre.
  double cost_weight = 2.0;
  double unsafe_cost = 30.0;  // R
  double unsafe_penalty = 10.0;
  double blocked_cost = kCostLethal;
  double blocked_penalty = 100.0;
  // Bounds the work (~0.13 us an expansion here, with the coarsening ~20 us): no path beyond it.
  // Round a 3 m wall: ~600.
  int max_expansions = 2500;
};

enum class CostmapPathResult : uint8_t {
  kFound,
  kStartOffMap,
  kGoalOffMap,
  kGoalBlocked,  // in the lethal core (a goal merely at or above blocked_cost is reached)
  kNoWay,        // every reachable cell expanded, the goal not among them
  kTooManyExpansions,
};

const char* to_string(CostmapPathResult r);

class CostmapPathPlanner {
 public:
  // The map the next plans run on: a coarsened copy of `map`, in cells of cell_m rounded to a
  // whole number of costmap cells (>= 1). ~20 us for the daemon's 240 x 240 at 0.1 m: once per
  // control step, however many plans follow.
  void set_map(const Costmap& map, double cell_m);
  // The path from `start` to `goal` (odom) on the last set_map's copy, start and goal included,
  // the cell centres between them; empty unless kFound.
  CostmapPathResult plan(Point2 start, Point2 goal, const CostmapPathConfig& config,
                         std::vector<Point2>& path);
  // Cells expanded by the last plan (its work).
  [[nodiscard]] int expansions() const { return expansions_; }

 private:
  struct Open {
    float f;
    int32_t cell;
  };
  int n_ = 0;          // planning cells per side (0: no map set)
  double cell_m_ = 0;  // their size
  double ox_ = 0, oy_ = 0;
  std::vector<uint8_t> cost_;    // n_ x n_, the worst costmap cell of each
  std::vector<float> g_;         // cost from the start
  std::vector<int32_t> parent_;  // -1: none
  std::vector<uint8_t> closed_;
  std::vector<Open> open_;  // binary heap on f
  int expansions_ = 0;
};

// True when a costmap cell at or above `cost` lies on the segment a -> b (sampled every half
// costmap cell).
bool segment_crosses(const Costmap& map, Point2 a, Point2 b, double cost);

}  // namespace core
