#include "sim/costmap_snapshot.hpp"

#include <fmt/format.h>

#include <cmath>

namespace sim {

namespace {
// A binary PGM of the map's cells, one pixel a cell, the top row the largest y; `pixel(i, j)`
// gives the cell's grey value.
template <typename Pixel>
std::string map_pgm(const core::Costmap& map, Pixel pixel) {
  const int n = map.cells();
  std::string out = fmt::format("P5\n{} {}\n255\n", n, n);
  out.reserve(out.size() + static_cast<size_t>(n) * static_cast<size_t>(n));
  for (int j = n - 1; j >= 0; --j) {
    for (int i = 0; i < n; ++i)
      out.push_back(static_cast<char>(pixel(i, j)));
  }
  return out;
}
}  // namespace

std::string costmap_pgm(const core::Costmap& map) {
  return map_pgm(map, [&](int i, int j) {
    const int cost = std::min<int>(map.cell(i, j), 100);
    return 255 - static_cast<int>(std::lround(cost * 2.55));
  });
}

std::string costmap_age_pgm(const core::Costmap& map) {
  return map_pgm(map, [&](int i, int j) {
    if (!map.obstacle(i, j)) return 255L;  // white
    const long steps = std::lround(map.obstacle_age_s(i, j) / core::Costmap::kObstacleAgeStepS);
    return 254 - std::min<long>(steps, 254);
  });
}

namespace {
std::string pose(const core::Pose2& p) {
  return fmt::format("[{:.4f}, {:.4f}, {:.4f}]", p.x_m, p.y_m, p.theta_rad);
}
}  // namespace

std::string costmap_yaml(const core::Costmap& map, const std::string& image_name,
                         const CostmapMarks& m) {
  // occupied_thresh: cost >= R (the controller's lethal) reads as occupied in a map viewer.
  std::string out = fmt::format(
      "image: {}\nresolution: {}\norigin: [{:.4f}, {:.4f}, 0.0]\nnegate: 0\n"
      "occupied_thresh: {:.3f}\nfree_thresh: 0.001\nmode: scale\n",
      image_name, map.resolution(), map.origin_x(), map.origin_y(), m.cost_threshold / 100.0);
  out += fmt::format("# companion: what the daemon knew (odom frame, metres, radians)\n");
  out += fmt::format("t_s: {:.3f}\nframe: odom\ncost_threshold: {}\n", m.t_s, m.cost_threshold);
  out += fmt::format("robot: {}\n", pose(m.robot_odom));
  out += m.has_person ? fmt::format("person: {}\n", pose(m.person_odom)) : "person: null\n";
  out += m.has_goal ? fmt::format("goal: {}\n", pose(m.goal_odom)) : "goal: null\n";
  auto path = [&](const char* key, const std::vector<core::Pose2>& poses) {
    out += fmt::format("{}: [", key);
    for (size_t i = 0; i < poses.size(); ++i)
      out += (i == 0 ? "" : ", ") + pose(poses[i]);
    out += "]\n";
  };
  if (!m.age_image.empty()) {
    out += fmt::format("obstacle_ages: {{image: {}, step_s: {}, settled_s: {}}}\n", m.age_image,
                       core::Costmap::kObstacleAgeStepS, m.obstacle_settled_s);
  }
  path("predicted_person", m.predicted_person);
  path("predicted_goal", m.predicted_goal);
  if (m.tracking) {
    out += fmt::format("plan_cost: {{tracking: {:.1f}, collision: {:.1f}, barrier: {:.1f}}}\n",
                       m.plan_tracking, m.plan_collision, m.plan_barrier);
  } else {
    out += "plan_cost: null\n";
  }
  return out;
}

}  // namespace sim
