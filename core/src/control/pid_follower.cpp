#include "core/control/pid_follower.hpp"

#include <algorithm>
#include <cmath>

namespace core {

void PidFollower::reset() {
  has_last_ = false;
  distance_integral_ = bearing_integral_ = 0;
  out_ = Twist{};
}

Twist PidFollower::step(const Point2& person, Nanos now) {
  const double distance = std::hypot(person.x_m, person.y_m);
  const double bearing = std::atan2(person.y_m, person.x_m);
  const double e_d = distance - cfg_.distance_m;
  double dt = 0;
  if (has_last_) dt = std::clamp(to_seconds(now - last_), 0.0, 0.1);
  double de_d = 0, de_b = 0;
  if (dt > 0) {
    de_d = (e_d - last_distance_error_) / dt;
    de_b = wrap_angle(bearing - last_bearing_) / dt;
    // Integrals clamped (anti-windup): they can at most add one limit's worth.
    distance_integral_ = std::clamp(distance_integral_ + e_d * dt,
                                    -cfg_.limits.vx / std::max(cfg_.ki_distance, 1e-9),
                                    cfg_.limits.vx / std::max(cfg_.ki_distance, 1e-9));
    bearing_integral_ = std::clamp(bearing_integral_ + bearing * dt,
                                   -cfg_.limits.wz / std::max(cfg_.ki_bearing, 1e-9),
                                   cfg_.limits.wz / std::max(cfg_.ki_bearing, 1e-9));
  }
  double vx =
      cfg_.kp_distance * e_d + cfg_.ki_distance * distance_integral_ + cfg_.kd_distance * de_d;
  double wz =
      cfg_.kp_bearing * bearing + cfg_.ki_bearing * bearing_integral_ + cfg_.kd_bearing * de_b;
  // Facing away from the person: turn first, do not drive.
  if (std::abs(bearing) > 1.2) vx = 0;
  vx = std::clamp(vx, -cfg_.limits.vx, cfg_.limits.vx);
  wz = std::clamp(wz, -cfg_.limits.wz, cfg_.limits.wz);
  // Within the base's accelerations from the previous output (the first step, with no elapsed
  // time known, keeps it: a start from rest begins at rest).
  const double dv = cfg_.linear_accel_mps2 * dt;
  const double dw = cfg_.angular_accel_radps2 * dt;
  vx = std::clamp(vx, out_.vx - dv, out_.vx + dv);
  wz = std::clamp(wz, out_.wz - dw, out_.wz + dw);
  out_ = Twist{vx, 0.0, wz};
  last_ = now;
  has_last_ = true;
  last_distance_error_ = e_d;
  last_bearing_ = bearing;
  return out_;
}

}  // namespace core
