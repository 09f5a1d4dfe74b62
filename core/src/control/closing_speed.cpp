#include "core/control/closing_speed.hpp"

#include <algorithm>
#include <cmath>

namespace core {

double max_closing_speed(double gap_m, double person_receding_mps, const ClosingSpeedConfig& c) {
  const double a = c.robot_decel_mps2;
  const double t = c.reaction_time_s;
  double room_m = std::max(gap_m - c.margin_m, 0.0);
  if (person_receding_mps > 0.0) {
    room_m += person_receding_mps * person_receding_mps / (2.0 * c.person_decel_mps2);
  }
  // v t + v^2 / (2 a) = room  ->  v = -a t + sqrt((a t)^2 + 2 a room)
  return std::max(-a * t + std::sqrt(a * t * a * t + 2.0 * a * room_m), 0.0);
}

ClosingSpeedResult limit_closing_speed(const Point2& person_in_base,
                                       const Point2& person_velocity_in_base, const Twist& u,
                                       const ClosingSpeedConfig& c, const TwistLimits& limits) {
  ClosingSpeedResult out;
  out.u = u;
  const Footprint& f = c.footprint;
  // The footprint's point nearest the person, and the direction from it to them.
  const Point2 near{std::clamp(person_in_base.x_m, f.x_min_m, f.x_max_m),
                    std::clamp(person_in_base.y_m, f.y_min_m, f.y_max_m)};
  double nx = person_in_base.x_m - near.x_m;
  double ny = person_in_base.y_m - near.y_m;
  double dist = std::hypot(nx, ny);
  out.gap_m = dist - c.person_radius_m;
  if (dist < 1e-9) {  // their centre inside the footprint: away from the robot's centre
    nx = person_in_base.x_m;
    ny = person_in_base.y_m;
    dist = std::hypot(nx, ny);
    if (dist < 1e-9) {
      nx = 1.0;
      ny = 0.0;
      dist = 1.0;
    }
    out.gap_m = -c.person_radius_m;
  }
  nx /= dist;
  ny /= dist;
  // Closing speed of the nearest point, n . (v + w z x r), as g . (vx, vy, wz).
  const double g0 = nx;
  const double g1 = ny;
  const double g2 = -nx * near.y_m + ny * near.x_m;
  auto closing = [&](const Twist& t) { return g0 * t.vx + g1 * t.vy + g2 * t.wz; };
  const double receding = nx * person_velocity_in_base.x_m + ny * person_velocity_in_base.y_m;
  out.max_closing_mps = max_closing_speed(out.gap_m, receding, c);
  out.closing_mps = closing(u);
  if (c.robot_decel_mps2 <= 0.0 || out.closing_mps <= out.max_closing_mps) return out;

  out.limited = true;
  const double excess = (out.closing_mps - out.max_closing_mps) / (g0 * g0 + g1 * g1 + g2 * g2);
  Twist v{u.vx - excess * g0, u.vy - excess * g1, u.wz - excess * g2};
  v.vx = std::clamp(v.vx, -limits.vx, limits.vx);
  v.vy = std::clamp(v.vy, -limits.vy, limits.vy);
  v.wz = std::clamp(v.wz, -limits.wz, limits.wz);
  const double after = closing(v);
  if (after > out.max_closing_mps) {  // the box undid part of it: slow the whole command
    const double s = out.max_closing_mps / after;  // after > max >= 0
    v = Twist{v.vx * s, v.vy * s, v.wz * s};
  }
  out.u = v;
  return out;
}

}  // namespace core
