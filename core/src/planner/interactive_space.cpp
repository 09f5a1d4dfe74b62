#include "core/planner/interactive_space.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace core {

std::string_view to_string(GoalStatus s) {
  switch (s) {
    case GoalStatus::kOk:
      return "ok";
    case GoalStatus::kNoFreePoint:
      return "no free point around the person";
    case GoalStatus::kNoPerson:
      return "no person";
    case GoalStatus::kNoCostmap:
      return "no costmap";
  }
  return "?";
}

InteractiveSpace::InteractiveSpace(const InteractiveSpaceConfig& config)
    : config_(config),
      cos_phi_(static_cast<size_t>(config.points)),
      sin_phi_(static_cast<size_t>(config.points)),
      candidates_(static_cast<size_t>(config.points)) {
  for (int i = 0; i < config.points; ++i) {
    const double phi = 2.0 * std::numbers::pi * i / config.points;
    cos_phi_[static_cast<size_t>(i)] = std::cos(phi);
    sin_phi_[static_cast<size_t>(i)] = std::sin(phi);
  }
}

void InteractiveSpace::update(const Pose2& person_base, const Pose2& robot_odom,
                              const Costmap& costmap) {
  free_count_ = 0;
  for (size_t i = 0; i < candidates_.size(); ++i) {
    Candidate& c = candidates_[i];
    const Point2 p = person_base.apply(point_in_person(i));
    c.base = Pose2{p.x_m, p.y_m, person_base.theta_rad};
    c.odom = robot_odom.apply(p);
    c.dist_human_m = std::hypot(p.x_m - person_base.x_m, p.y_m - person_base.y_m);
    c.dist_robot_m = std::hypot(p.x_m, p.y_m);
    c.cost = costmap.at(c.odom.x_m, c.odom.y_m);
    const double ahead_of_person_m = std::max(0.0, config_.a_m * cos_phi_[i]);
    c.objective = config_.alpha * c.dist_human_m + config_.beta * c.dist_robot_m +
                  config_.gamma * c.cost + config_.delta * ahead_of_person_m;
    c.free = c.cost < config_.cost_threshold;
    free_count_ += c.free ? 1U : 0U;
  }
}

Selection select_by_objective(const InteractiveSpace& space) {
  Selection s;
  s.status = GoalStatus::kNoFreePoint;
  double best = std::numeric_limits<double>::infinity();
  const auto cs = space.candidates();
  for (size_t i = 0; i < cs.size(); ++i) {
    if (cs[i].free && cs[i].objective < best) {
      best = cs[i].objective;
      s.index = static_cast<int>(i);
      s.goal_base = cs[i].base;
      s.status = GoalStatus::kOk;
    }
  }
  return s;
}

}  // namespace core
