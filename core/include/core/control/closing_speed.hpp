#pragma once
// Speed and separation monitoring toward the followed person (after ISO/TS 15066's SSM): the
// robot never moves toward the person faster than it can stop from before its footprint
// reaches them, counting how they may move toward it meanwhile.
//   gap D: the distance from the robot's footprint (a box in base_link) to the person's body
//          (a circle), less `margin_m`;
//   n: the unit direction from the footprint's nearest point to the person's centre;
//   v_r: that point's velocity toward the person, n . (v + w x r), linear in the command;
//   v_p: the person's velocity away from the robot, n . v_person (negative: toward it); their
//        speed toward the robot, -v_p, may grow at a_h (turning into it, stopping) up to what
//        they do not already spend walking away: |v_person| - max(v_p, 0) (one walking
//        straight away may stop, not come back; one walking across may turn into the robot);
//   the robot stops in T = t_r + v_r / a_r (reaction time, then braking at a_r), having moved
//   v_r t_r + v_r^2 / (2 a_r); the person meanwhile comes closer by the integral of the above;
//   limit: the sum of the two <= D (convex in v_r: the largest root, by bisection).
// The limit is never negative, so a command is only ever slowed, never turned into motion
// away: standing still always satisfies it (the person who walks toward a standing robot is
// theirs to avoid, as with any obstacle; the DCBF keeps the robot out of their ellipse).
// The command is the least change (Euclidean in vx, vy, wz) that meets the limit, clipped to the
// velocity box, then scaled toward zero if the box pushed it back over. Why it exists: with q^d
// on the ellipse's edge, a robot catching up at 1.5 m/s met the person's turn faster than its
// 1.5 m/s^2 brakes could stop in the 0.2-0.4 m left between the bodies (docs/EVALUATION.md).
#include <algorithm>
#include <cmath>

#include "core/control/dcbf_repair.hpp"
#include "core/geometry/pose2.hpp"

namespace core {

struct Footprint {
  double x_min_m = -0.35, x_max_m = 0.35, y_min_m = -0.30, y_max_m = 0.30;  // base_link box
  // The box's point nearest `p` (base_link; `p` itself when inside).
  [[nodiscard]] Point2 nearest(const Point2& p) const {
    return {std::clamp(p.x_m, x_min_m, x_max_m), std::clamp(p.y_m, y_min_m, y_max_m)};
  }
  // Whether the box grown by `grow_m` on every side covers `p` (base_link).
  [[nodiscard]] bool covers(const Point2& p, double grow_m = 0.0) const {
    return p.x_m >= x_min_m - grow_m && p.x_m <= x_max_m + grow_m && p.y_m >= y_min_m - grow_m &&
           p.y_m <= y_max_m + grow_m;
  }
  // Its farthest point from base_link's origin (m): closer than this it can touch an obstacle.
  [[nodiscard]] double circumscribed_radius_m() const {
    return std::hypot(std::max(std::abs(x_min_m), std::abs(x_max_m)),
                      std::max(std::abs(y_min_m), std::abs(y_max_m)));
  }
};

struct ClosingSpeedConfig {
  double robot_decel_mps2 = 0;  // a_r; 0 = off
  // a_h: how fast the person's velocity toward the robot may grow (turning into it, stopping in
  // front of it); 3 m/s^2 is a walking person's lateral acceleration in a quick turn.
  double person_accel_mps2 = 3.0;
  double reaction_time_s = 0.05;  // t_r: command latency and the control period
  double margin_m = 0.10;         // gap left between the bodies after a stop
  double person_radius_m = 0.25;
  Footprint footprint;
};

struct ClosingSpeedResult {
  Twist u;
  bool limited = false;        // the command was slowed
  double gap_m = 0;            // footprint to the person's body (negative: overlapping)
  double closing_mps = 0;      // the command's speed of the nearest point toward the person
  double max_closing_mps = 0;  // what the limit allows
};

// How much closer the person comes in `time_s` (m; negative: farther), walking away from the
// robot at `receding_mps` (negative: toward it) at `speed_mps` in all, turning toward it at up to
// `accel_mps2`.
double person_approach_m(double time_s, double receding_mps, double speed_mps, double accel_mps2);

// How much the gap closes (m) from a command closing at `closing_mps` until the robot has
// stopped: its reaction and braking, plus person_approach_m over that time.
double stopping_distance_m(double closing_mps, double receding_mps, double speed_mps,
                           const ClosingSpeedConfig& c);

// The largest speed toward the person that still stops in time (>= 0).
double max_closing_speed(double gap_m, double receding_mps, double speed_mps,
                         const ClosingSpeedConfig& c);

// The nearest the robot's centre may follow the person's centre (m) and still keep pace under
// the limit: a robot on the ray `toward_person` (its own axes; any length), moving with the
// person (`person_velocity`, the same axes), closes at the speed they recede, which the limit
// allows only with a gap of margin + stopping_distance_m. 0 when the person does not recede
// from that side (beside or ahead of them: the limit does not hold the robot back) or the limit
// is off. At 1 m/s straight behind, with the defaults: 1.08 m (the ellipse's a: 1.0 m).
double follow_standoff_m(const Point2& toward_person, const Point2& person_velocity,
                         const ClosingSpeedConfig& c);

// `person_in_base` and `person_velocity_in_base` (the person's own velocity, base_link axes).
ClosingSpeedResult limit_closing_speed(const Point2& person_in_base,
                                       const Point2& person_velocity_in_base, const Twist& u,
                                       const ClosingSpeedConfig& c, const TwistLimits& limits);

}  // namespace core
