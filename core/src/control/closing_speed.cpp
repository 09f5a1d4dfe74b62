#include "core/control/closing_speed.hpp"

#include <algorithm>
#include <cmath>

namespace core {

double person_approach_m(double time_s, double receding_mps, double speed_mps, double accel_mps2) {
  // Their speed toward the robot starts at -receding and grows at accel up to a cap: what they
  // do not already spend walking away (one walking straight away may stop, not come back; one
  // walking across or toward the robot may turn into it at their speed).
  const double start = -receding_mps;
  const double cap =
      std::max(std::clamp(speed_mps - std::max(receding_mps, 0.0), 0.0, speed_mps), start);
  if (accel_mps2 <= 0.0) return start * time_s;
  const double ramp_s = (cap - start) / accel_mps2;  // >= 0
  if (time_s <= ramp_s) return start * time_s + 0.5 * accel_mps2 * time_s * time_s;
  return start * ramp_s + 0.5 * accel_mps2 * ramp_s * ramp_s + cap * (time_s - ramp_s);
}

double stopping_distance_m(double closing_mps, double receding_mps, double speed_mps,
                           const ClosingSpeedConfig& c) {
  // The robot at v stops after T = t + v / a, having moved v t + v^2 / (2 a) toward the person;
  // meanwhile they come person_approach_m(T) closer.
  const double a = c.robot_decel_mps2;
  const double t = c.reaction_time_s;
  const double v = closing_mps;
  return v * t + v * v / (2.0 * a) +
         person_approach_m(t + v / a, receding_mps, speed_mps, c.person_accel_mps2);
}

double max_closing_speed(double gap_m, double receding_mps, double speed_mps,
                         const ClosingSpeedConfig& c) {
  const double room_m = std::max(gap_m - c.margin_m, 0.0);
  // Both terms of stopping_distance_m are convex in v (the person's speed toward the robot only
  // grows), so the speeds that keep the sum within the room are [0, v_max].
  auto closed_m = [&](double v) { return stopping_distance_m(v, receding_mps, speed_mps, c); };
  if (c.robot_decel_mps2 <= 0.0 || closed_m(0.0) > room_m) return 0.0;
  double lo = 0.0;
  double hi = 4.0;
  for (int i = 0; i < 16 && closed_m(hi) <= room_m; ++i) {
    lo = hi;
    hi *= 2.0;
  }
  for (int i = 0; i < 40; ++i) {  // 4 m/s / 2^40: far below anything the base resolves
    const double mid = 0.5 * (lo + hi);
    (closed_m(mid) <= room_m ? lo : hi) = mid;
  }
  return lo;
}

double follow_standoff_m(const Point2& toward_person, const Point2& person_velocity,
                         const ClosingSpeedConfig& c) {
  const double norm = std::hypot(toward_person.x_m, toward_person.y_m);
  if (c.robot_decel_mps2 <= 0.0 || norm < 1e-9) return 0.0;
  const double ux = toward_person.x_m / norm;
  const double uy = toward_person.y_m / norm;
  // Keeping pace, the robot closes at the speed the person recedes: the limit lets it when the
  // gap holds what both need to stop from there (a person walking toward the point needs none).
  const double receding = ux * person_velocity.x_m + uy * person_velocity.y_m;
  if (receding <= 0.0) return 0.0;
  const double speed = std::hypot(person_velocity.x_m, person_velocity.y_m);
  const double body_gap_m =
      c.person_radius_m + c.margin_m + stopping_distance_m(receding, receding, speed, c);
  // The nearest the person's centre may be to the footprint box, along the ray: the box is
  // convex, so its distance to the ray's points grows with the distance along it (bisection).
  const Footprint& f = c.footprint;
  auto box_distance_sq = [&](double d) {  // squared: no square root in the loop
    const Point2 q{d * ux, d * uy};
    const Point2 n = f.nearest(q);
    return (q.x_m - n.x_m) * (q.x_m - n.x_m) + (q.y_m - n.y_m) * (q.y_m - n.y_m);
  };
  const double body_gap_sq = body_gap_m * body_gap_m;
  double lo = 0.0;
  double hi = std::hypot(std::max(-f.x_min_m, f.x_max_m), std::max(-f.y_min_m, f.y_max_m)) +
              body_gap_m;         // the box's far corner plus the gap: always far enough
  for (int i = 0; i < 24; ++i) {  // the bracket (< 4 m) / 2^24: under a micrometre, from above
    const double mid = 0.5 * (lo + hi);
    (box_distance_sq(mid) < body_gap_sq ? lo : hi) = mid;
  }
  return hi;
}

ClosingSpeedResult limit_closing_speed(const Point2& person_in_base,
                                       const Point2& person_velocity_in_base, const Twist& u,
                                       const ClosingSpeedConfig& c, const TwistLimits& limits) {
  ClosingSpeedResult out;
  out.u = u;
  if (c.robot_decel_mps2 <= 0.0) return out;  // off
  const Footprint& f = c.footprint;
  // The footprint's point nearest the person, and the direction from it to them.
  const Point2 near = f.nearest(person_in_base);
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
  const double speed = std::hypot(person_velocity_in_base.x_m, person_velocity_in_base.y_m);
  out.max_closing_mps = max_closing_speed(out.gap_m, receding, speed, c);
  out.closing_mps = closing(u);
  if (out.closing_mps <= out.max_closing_mps) return out;

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
