// The costmap path (MPPI's path sample, mppi.path_guide): A* round obstacles on a coarsened
// costmap, with its refusals.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/control/costmap_path.hpp"
#include "core/perception/voxel_grid.hpp"

using core::CostmapPathResult;
using core::Point2;
using core::Pose2;
using namespace std::chrono_literals;

namespace {

struct Segment {
  Point2 a, b;
};

// A 10 m costmap centred on (cx, cy) with obstacles along the segments (marked by rays from
// high above, so nothing on the floor is cleared).
core::Costmap map_with(const std::vector<Segment>& walls, double cx = 1.5, double cy = 0.0) {
  core::VoxelGridConfig gc;
  gc.size_xy_m = 10.0;
  core::VoxelGrid g(gc);
  g.recentre(cx, cy);
  std::vector<core::Ray> rays;
  for (const Segment& w : walls) {
    const double length = std::hypot(w.b.x_m - w.a.x_m, w.b.y_m - w.a.y_m);
    const int n = std::max(1, static_cast<int>(length / 0.02));
    for (int i = 0; i <= n; ++i) {
      const double f = static_cast<double>(i) / n;
      rays.push_back({{cx, cy - 3.0, 3.0},
                      {w.a.x_m + f * (w.b.x_m - w.a.x_m), w.a.y_m + f * (w.b.y_m - w.a.y_m), 0.5}});
    }
  }
  g.insert(rays, Pose2{30, 30, 0}, std::nullopt, 1s);
  core::Costmap m;
  m.build(g, core::CostmapConfig{}, 1s);
  return m;
}

double length_of(const std::vector<Point2>& path) {
  double l = 0;
  for (size_t i = 1; i < path.size(); ++i)
    l += std::hypot(path[i].x_m - path[i - 1].x_m, path[i].y_m - path[i - 1].y_m);
  return l;
}

}  // namespace

TEST(CostmapPath, OnAnOpenFloorItIsTheStraightLine) {
  const core::Costmap map = map_with({});
  core::CostmapPathPlanner planner;
  planner.set_map(map, 0.1);
  std::vector<Point2> path;
  const Point2 start{0.0, 0.0};
  const Point2 goal{3.0, 1.0};
  ASSERT_EQ(planner.plan(start, goal, {}, path), CostmapPathResult::kFound);
  EXPECT_DOUBLE_EQ(path.front().x_m, start.x_m);
  EXPECT_DOUBLE_EQ(path.back().y_m, goal.y_m);
  // 8-connected on 0.1 m cells: the octile length (2 m straight + 1 m diagonal = 3.41 m), not
  // the line's 3.16 m; steps of one cell (the exact ends: up to half a cell more).
  EXPECT_LT(length_of(path), 2.0 + std::sqrt(2.0) + 0.1);
  for (size_t i = 1; i < path.size(); ++i) {
    EXPECT_LT(std::hypot(path[i].x_m - path[i - 1].x_m, path[i].y_m - path[i - 1].y_m), 0.22);
  }
  EXPECT_FALSE(core::segment_crosses(map, start, goal, core::kCostLethal));
}

// A wall between robot and goal, longer on one side: the path takes the short side, and never
// enters a lethal cell. Mirrored, the other side.
TEST(CostmapPath, GoesRoundAWallOnItsShortSide) {
  for (const double sign : {1.0, -1.0}) {
    const core::Costmap map = map_with({{{1.5, -0.4 * sign}, {1.5, 3.0 * sign}}});
    core::CostmapPathPlanner planner;
    planner.set_map(map, 0.1);
    std::vector<Point2> path;
    const Point2 start{0.0, 0.0};
    const Point2 goal{3.0, 0.0};
    ASSERT_TRUE(core::segment_crosses(map, start, goal, core::kCostLethal));
    ASSERT_EQ(planner.plan(start, goal, {}, path), CostmapPathResult::kFound);
    double crossing_y = 0;  // where the path passes the wall's line
    for (size_t i = 1; i < path.size(); ++i) {
      EXPECT_LT(map.at(path[i].x_m, path[i].y_m), core::kCostLethal) << i;
      if (path[i - 1].x_m < 1.5 && path[i].x_m >= 1.5) crossing_y = path[i].y_m;
    }
    EXPECT_LT(sign * crossing_y, -0.4 - 0.35) << "below the wall's short end, clear of its core";
    EXPECT_LT(length_of(path), 6.0) << "not round the long end (> 8 m)";
    EXPECT_GT(planner.expansions(), 0);
  }
}

// The cost of the inflation band: two gaps, one through the unsafe band (cost >= R) and a
// detour through free space, which the path prefers while it is not much longer.
TEST(CostmapPath, PrefersFreeSpaceToTheUnsafeBand) {
  // Two posts 1.3 m apart on the straight line: their 0.75 m unsafe bands overlap in the gap.
  const core::Costmap map = map_with({{{1.5, -0.65}, {1.5, -0.6}}, {{1.5, 0.6}, {1.5, 0.65}}});
  ASSERT_GE(map.cost(1.5, 0.0), 30.0);
  ASSERT_LT(map.at(1.5, 0.0), core::kCostLethal);
  core::CostmapPathPlanner planner;
  planner.set_map(map, 0.1);
  std::vector<Point2> path;
  ASSERT_EQ(planner.plan({0.0, 0.0}, {3.0, 0.0}, {}, path), CostmapPathResult::kFound);
  bool through_gap = false;
  for (const Point2& p : path)
    through_gap = through_gap || (std::abs(p.x_m - 1.5) < 0.1 && std::abs(p.y_m) < 0.5);
  EXPECT_FALSE(through_gap) << "round a post, not through the band between them";
  // Without the band's penalty the gap is the shortest way.
  core::CostmapPathConfig flat;
  flat.cost_weight = 0;
  flat.unsafe_penalty = 0;
  ASSERT_EQ(planner.plan({0.0, 0.0}, {3.0, 0.0}, flat, path), CostmapPathResult::kFound);
  through_gap = false;
  for (const Point2& p : path)
    through_gap = through_gap || (std::abs(p.x_m - 1.5) < 0.1 && std::abs(p.y_m) < 0.5);
  EXPECT_TRUE(through_gap);
}

TEST(CostmapPath, RefusesWhatItCannotPlan) {
  // A box round (3, 0): no way in.
  const core::Costmap map = map_with({{{2.0, -1.0}, {4.0, -1.0}},
                                      {{4.0, -1.0}, {4.0, 1.0}},
                                      {{4.0, 1.0}, {2.0, 1.0}},
                                      {{2.0, 1.0}, {2.0, -1.0}}});
  core::CostmapPathPlanner planner;
  planner.set_map(map, 0.1);
  std::vector<Point2> path{{9, 9}};
  core::CostmapPathConfig whole_map;  // 100 x 100 cells: the bound must not end it first
  whole_map.max_expansions = 20000;
  EXPECT_EQ(planner.plan({0.0, 0.0}, {3.0, 0.0}, whole_map, path), CostmapPathResult::kNoWay);
  EXPECT_TRUE(path.empty());
  core::CostmapPathConfig tight;
  tight.max_expansions = 50;
  EXPECT_EQ(planner.plan({0.0, 0.0}, {3.0, 0.0}, tight, path),
            CostmapPathResult::kTooManyExpansions);
  EXPECT_LE(planner.expansions(), 51);
  EXPECT_EQ(planner.plan({0.0, 0.0}, {2.0, 0.0}, {}, path), CostmapPathResult::kGoalBlocked);
  EXPECT_EQ(planner.plan({0.0, 0.0}, {30.0, 0.0}, {}, path), CostmapPathResult::kGoalOffMap);
  EXPECT_EQ(planner.plan({-30.0, 0.0}, {0.5, 0.0}, {}, path), CostmapPathResult::kStartOffMap);
  EXPECT_EQ(planner.plan({std::nan(""), 0.0}, {0.5, 0.0}, {}, path),
            CostmapPathResult::kStartOffMap);
  planner.set_map(core::Costmap{}, 0.1);  // an empty map
  EXPECT_EQ(planner.plan({0.0, 0.0}, {0.5, 0.0}, {}, path), CostmapPathResult::kStartOffMap);
  EXPECT_EQ(core::CostmapPathPlanner{}.plan({0.0, 0.0}, {0.5, 0.0}, {}, path),
            CostmapPathResult::kStartOffMap)
      << "no map set";
  EXPECT_STREQ(core::to_string(CostmapPathResult::kNoWay), "no way");
}

// The robot may stand in the lethal band (pushed there, or the map moved): the path leads out.
TEST(CostmapPath, StartsFromABlockedCell) {
  const core::Costmap map = map_with({{{1.5, -0.4}, {1.5, 3.0}}});
  const Point2 start{1.3, 1.0};  // 0.2 m from the wall: inside its lethal core
  ASSERT_EQ(map.at(start.x_m, start.y_m), core::kCostLethal);
  core::CostmapPathPlanner planner;
  planner.set_map(map, 0.1);
  std::vector<Point2> path;
  ASSERT_EQ(planner.plan(start, {0.0, 1.0}, {}, path), CostmapPathResult::kFound);
  EXPECT_LT(length_of(path), 1.6) << "straight out, away from the wall";
  EXPECT_LT(path[path.size() / 2].x_m, start.x_m);
  // Behind the wall, the way is out on the near side and round its short end, not through it.
  ASSERT_EQ(planner.plan(start, {2.5, 1.0}, {}, path), CostmapPathResult::kFound);
  double least_y = 9;
  for (const Point2& p : path)
    least_y = std::min(least_y, p.y_m);
  EXPECT_LT(least_y, -0.4 - 0.35);
}
