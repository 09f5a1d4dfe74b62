#include "core/safety/motion_gate.hpp"

#include <algorithm>
#include <cmath>

namespace core {
namespace {

bool finite(const BodyVelocity& v) {
  return std::isfinite(v.vx_mps) && std::isfinite(v.vy_mps) && std::isfinite(v.wz_radps);
}

// Moves `v` toward 0 by at most `step`, never past it.
double toward_zero(double v, double step) {
  if (v > 0.0) return std::max(0.0, v - step);
  if (v < 0.0) return std::min(0.0, v + step);
  return 0.0;
}

}  // namespace

BodyVelocity MotionGate::update(bool motion_allowed, const BodyVelocity& requested, Nanos now) {
  const double dt = has_last_time_ ? std::max(0.0, to_seconds(now - last_time_)) : 0.0;
  last_time_ = now;
  has_last_time_ = true;

  const bool request_ok = finite(requested);
  if (motion_allowed && !request_ok) ++rejected_non_finite_;

  if (motion_allowed && request_ok) {
    stopping_ = false;
    last_ = requested;
    return last_;
  }

  if (!stopping_) {
    stopping_ = true;
    stop_started_ = now;
  }
  if (!finite(last_) || now - stop_started_ >= limits_.max_stop_time) {
    last_ = BodyVelocity{};
    return last_;
  }
  // Decelerate the planar speed along its own direction (the path does not bend while
  // stopping), and the yaw rate independently.
  const double speed = std::hypot(last_.vx_mps, last_.vy_mps);
  const double new_speed = toward_zero(speed, limits_.linear_decel_mps2 * dt);
  const double scale = speed > 0.0 ? new_speed / speed : 0.0;
  last_.vx_mps *= scale;
  last_.vy_mps *= scale;
  last_.wz_radps = toward_zero(last_.wz_radps, limits_.angular_decel_radps2 * dt);
  return last_;
}

}  // namespace core
