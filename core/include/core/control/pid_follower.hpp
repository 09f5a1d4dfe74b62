#pragma once
// The evaluation's PID follower baseline (reference/evaluation.md): two loops on the person's
// position in base_link, bearing -> wz and distance -> vx, holding `distance_m` (1 m: "behind
// the person" by following them). No lateral motion, no obstacle avoidance, no barrier: it is
// there to show what the method adds. Pure: time is passed in.
#include "core/control/dcbf_repair.hpp"
#include "core/geometry/pose2.hpp"
#include "core/time.hpp"

namespace core {

struct PidFollowerConfig {
  double distance_m = 1.0;
  double kp_distance = 1.2, ki_distance = 0.1, kd_distance = 0.2;  // (m/s) per m
  double kp_bearing = 2.0, ki_bearing = 0.0, kd_bearing = 0.1;     // (rad/s) per rad
  TwistLimits limits;
  double linear_accel_mps2 = 1.5;
  double angular_accel_radps2 = 3.0;
};

class PidFollower {
 public:
  explicit PidFollower(const PidFollowerConfig& config) : cfg_(config) {}
  // `person`: the person's position in base_link now.
  Twist step(const Point2& person, Nanos now);
  void reset();

 private:
  PidFollowerConfig cfg_;
  bool has_last_ = false;
  Nanos last_{0};
  double last_distance_error_ = 0, last_bearing_ = 0;
  double distance_integral_ = 0, bearing_integral_ = 0;
  Twist out_;
};

}  // namespace core
