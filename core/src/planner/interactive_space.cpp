#include "core/planner/interactive_space.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
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
                              const Costmap& costmap, const Point2& person_velocity_base,
                              double person_yaw_rate_radps) {
  free_count_ = 0;
  // The person's velocity in their own frame: a robot at a point of W faces their heading, so
  // its axes are theirs (only the standoff reads it).
  const Point2 velocity_person =
      config_.speed_standoff ? Pose2{0.0, 0.0, -person_base.theta_rad}.rotate(person_velocity_base)
                             : Point2{};
  for (size_t i = 0; i < candidates_.size(); ++i) {
    Candidate& c = candidates_[i];
    // G weighs the design point (the paper's W): the standoff below moves the diagonal points
    // behind out farther than the one straight behind (the footprint's corner is nearer the
    // person there), and alpha < 0 would then prefer them.
    const Point2 design = person_base.apply(point_in_person(i));
    c.dist_human_m = std::hypot(design.x_m - person_base.x_m, design.y_m - person_base.y_m);
    c.dist_robot_m = std::hypot(design.x_m, design.y_m);
    Point2 in_person = point_in_person(i);
    if (config_.speed_standoff) {
      const double d = std::hypot(in_person.x_m, in_person.y_m);
      double standoff =
          follow_standoff_m({-in_person.x_m, -in_person.y_m}, velocity_person, config_.closing);
      if (config_.speed_standoff_max_m > 0.0) {
        standoff = std::min(standoff, config_.speed_standoff_max_m);
      }
      if (d > 1e-9 && standoff > d) {
        in_person = {in_person.x_m * standoff / d, in_person.y_m * standoff / d};
      }
    }
    // Where the robot is to be, and where it must be free.
    const Point2 p = person_base.apply(in_person);
    c.base = Pose2{p.x_m, p.y_m, person_base.theta_rad};
    c.odom = robot_odom.apply(p);
    c.cost = costmap.at(c.odom.x_m, c.odom.y_m);
    const double ahead_of_person_m = std::max(0.0, config_.a_m * cos_phi_[i]);
    const double inside_of_turn = std::max(0.0, person_yaw_rate_radps * config_.b_m * sin_phi_[i]);
    c.objective = config_.alpha * c.dist_human_m + config_.beta * c.dist_robot_m +
                  config_.gamma * c.cost + config_.delta * ahead_of_person_m +
                  config_.turn_inside * inside_of_turn;
    c.free = c.cost < config_.cost_threshold;
    free_count_ += c.free ? 1U : 0U;
  }
}

Selection select_by_objective(const InteractiveSpace& space, int previous_index) {
  Selection s;
  s.status = GoalStatus::kNoFreePoint;
  double best = std::numeric_limits<double>::infinity();
  const auto cs = space.candidates();
  const int n = static_cast<int>(cs.size());
  const double switch_cost =
      previous_index >= 0 && previous_index < n ? space.config().switch_cost : 0.0;
  for (size_t i = 0; i < cs.size(); ++i) {
    if (!cs[i].free) continue;
    const int step = std::abs(static_cast<int>(i) - previous_index);
    const double g = cs[i].objective + switch_cost * std::min(step, n - step);
    if (g < best) {
      best = g;
      s.index = static_cast<int>(i);
      s.goal_base = cs[i].base;
      s.status = GoalStatus::kOk;
    }
  }
  return s;
}

}  // namespace core
