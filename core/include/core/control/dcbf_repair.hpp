#pragma once
// The discrete-time control barrier function of the paper (section V) and the QP repair of the
// first control.
//   h(p) = x'^2 / a^2 + y'^2 / b^2 - 1, with (x', y') the robot's position in the person's frame;
//   safe: h >= 0; the DCBF condition over one step: h_{k+1} >= (1 - delta) h_k.
// Repair: minimise |u - u+|^2 subject to the condition linearised in (vx, vy) and the velocity
// box. h is convex in position and the next position is affine in (vx, vy), so the linearisation
// is a lower bound: a control that satisfies it satisfies the true condition (conservative).
// The QP (one half-space and a box) is solved exactly through its one-dimensional dual.
#include <array>

#include "core/geometry/pose2.hpp"

namespace core {

struct Ellipse {
  double a_m = 1.0;
  double b_m = 0.7;
};

double barrier(const Pose2& person, const Point2& robot, const Ellipse& e);

struct Twist {
  double vx = 0, vy = 0, wz = 0;  // body frame: m/s, m/s, rad/s
};

struct TwistLimits {
  double vx = 1.8, vy = 1.5, wz = 2.0;  // symmetric boxes
};

struct RepairResult {
  Twist u;
  bool modified = false;  // the nominal control violated the (linearised) condition
  bool feasible = true;   // false: no control in the box satisfies it; u does its best
  double h_now = 0;       // h at the robot's current position
  double h_next = 0;      // true h at the next step with u
};

// `robot` now (odom), `person_now` and `person_next` (odom) one step `dt_s` apart, nominal `u`.
RepairResult repair(const Pose2& robot, const Pose2& person_now, const Pose2& person_next,
                    const Twist& u, double dt_s, double delta, const Ellipse& e,
                    const TwistLimits& limits);

}  // namespace core
