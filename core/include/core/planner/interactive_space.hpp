#pragma once
// The paper's human-robot interactive space (section III):
//   W: n design points on the ellipse (a, b) around the person, in the human frame
//      q^h_i = (a cos phi_i, b sin phi_i), phi_i = 2 pi (i - 1) / n, moved into base_link with the
//      person's pose (the point's heading is the person's heading);
//   P: the points of W whose costmap cost l(q) is below R (cost scale:
//   core/perception/costmap.hpp); G(P_i) = alpha |P_i - q_h| + beta |P_i| + gamma l(P_i) (distances
//   in base_link, metres), plus ours, not the paper's: delta max(0, x^h_i), x^h_i = a cos phi_i how
//   far the point is ahead of the person (a leading robot is cut off by whatever the person turns
//   past; behind them is the way they came); the objective selector picks argmin G over P. With P
//   empty (the person is surrounded) there is no goal, and the reason says so.
// Pure; fixed-size buffers set at construction.
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "core/control/closing_speed.hpp"
#include "core/geometry/pose2.hpp"
#include "core/perception/costmap.hpp"

namespace core {

struct InteractiveSpaceConfig {
  int points = 64;               // n
  double a_m = 1.0;              // semi-axis along the person's heading
  double b_m = 0.7;              // semi-axis to the person's side
  double cost_threshold = 30.0;  // R: a point with l(q) >= R is not in P
  double alpha = -16.0;          // weight of the distance to the person (< 0: the far points)
  double beta = 4.0;             // weight of the distance to the robot (= the shipped yaml)
  double gamma = 0.02;           // weight of the costmap cost
  double delta = 4.0;            // weight of how far the point is ahead of the person (ours)
  // Ours: G of a point plus this much per index step (wrapped) from the point chosen last, the
  // paper's action-smoothness reward r^a = -sigma_a |a_t - a_(t-1)| as a cost: on a near tie
  // q^d stays where it is rather than jumping round the person. 0: the paper's G.
  double switch_cost = 0.0;
  // Ours: G of a point plus turn_inside * max(0, omega * y^h_i), omega the person's turn rate
  // (rad/s, + left), y^h_i = b sin phi_i how far the point is to their left: the points on the
  // inside of a turn cost more the sharper it is. A robot there is where the turning person
  // walks (docs/eval/SESSIONS.md, twenty-fifth and thirtieth sessions). 0: the paper's G.
  double turn_inside = 0.0;
  // Ours: when true, a point of W nearer the person than the robot may follow them under the
  // closing-speed limit (follow_standoff_m with `closing`, at the person's velocity) is moved
  // out along its ray to that distance: its cost, whether it is free, and q^d are taken there;
  // G's distance terms stay the design point's (the selection is the paper's). The robot is
  // held there anyway; q^d there makes e measure tracking, not the safety gap, and keeps the
  // controller from pulling against the limit. false: the paper's fixed ellipse.
  bool speed_standoff = false;
  // The farthest the standoff moves a point from the person (m; 0: no cap). Beyond it the
  // closing-speed limit holds the robot and the plan pulls toward q^d against it, as with the
  // fixed ellipse: at 1.7 m/s the uncapped point is ~1.8 m back, at the 2 m loss rule's edge.
  double speed_standoff_max_m = 0.0;
  // The time constant of the low-pass on the person's velocity that the standoff reads
  // (core/planner/standoff_velocity.hpp; 0: unfiltered).
  double speed_standoff_filter_s = 0.0;
  ClosingSpeedConfig closing;
};

struct Candidate {
  Pose2 base;   // in base_link; theta = the person's heading (speed_standoff: moved out)
  Point2 odom;  // where the costmap is looked up (the same point)
  double dist_human_m = 0;  // of the design point (G's terms)
  double dist_robot_m = 0;  // of the design point
  double cost = 0;          // l(q), 0..100
  double objective = 0;     // G
  bool free = false;        // in P
};

class InteractiveSpace {
 public:
  explicit InteractiveSpace(const InteractiveSpaceConfig& config);

  // W and P for the person (base_link) seen from the robot (its pose in odom, for the costmap);
  // `person_velocity_base`: their velocity in base_link axes (used by speed_standoff only);
  // `person_yaw_rate_radps`: their turn rate (used by turn_inside only).
  void update(const Pose2& person_base, const Pose2& robot_odom, const Costmap& costmap,
              const Point2& person_velocity_base = {}, double person_yaw_rate_radps = 0.0);

  [[nodiscard]] std::span<const Candidate> candidates() const { return candidates_; }
  [[nodiscard]] size_t free_count() const { return free_count_; }
  [[nodiscard]] const InteractiveSpaceConfig& config() const { return config_; }
  // Design point i of W in the person's frame (x along their heading): (a cos phi_i,
  // b sin phi_i); speed_standoff may move the candidate out from it.
  [[nodiscard]] Point2 point_in_person(size_t i) const {
    return {config_.a_m * cos_phi_[i], config_.b_m * sin_phi_[i]};
  }

 private:
  InteractiveSpaceConfig config_;
  std::vector<double> cos_phi_, sin_phi_;
  std::vector<Candidate> candidates_;
  size_t free_count_ = 0;
};

enum class GoalStatus : uint8_t { kOk = 0, kNoFreePoint, kNoPerson, kNoCostmap };
std::string_view to_string(GoalStatus s);

struct Selection {
  GoalStatus status = GoalStatus::kNoPerson;
  int index = -1;   // into W (0 .. n - 1)
  Pose2 goal_base;  // q^d in base_link
};

// The objective selector: argmin G over P (ties: the lowest index, so it is deterministic).
// `previous_index`: the point of W chosen last (-1: none), from which switch_cost counts.
Selection select_by_objective(const InteractiveSpace& space, int previous_index = -1);

}  // namespace core
