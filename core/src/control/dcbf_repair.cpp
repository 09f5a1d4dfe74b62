#include "core/control/dcbf_repair.hpp"

#include <algorithm>
#include <cmath>

namespace core {

double barrier(const Pose2& person, const Point2& robot, const Ellipse& e) {
  const Point2 r = person.inverse().apply(robot);
  return r.x_m * r.x_m / (e.a_m * e.a_m) + r.y_m * r.y_m / (e.b_m * e.b_m) - 1.0;
}

RepairResult repair(const Pose2& robot, const Pose2& person_now, const Pose2& person_next,
                    const Twist& u, double dt_s, double delta, const Ellipse& e,
                    const TwistLimits& limits) {
  RepairResult out;
  out.u = u;
  out.h_now = barrier(person_now, {robot.x_m, robot.y_m}, e);
  // Next robot position in the person's next frame, affine in (vx, vy): p' = p0 + J v.
  const double c = std::cos(robot.theta_rad);
  const double s = std::sin(robot.theta_rad);
  const Pose2 inv = person_next.inverse();
  const Point2 p0 = inv.apply({robot.x_m, robot.y_m});
  const double ci = std::cos(inv.theta_rad);
  const double si = std::sin(inv.theta_rad);
  // d(odom position)/d(vx, vy) = dt R(theta_robot); then rotated into the person's frame.
  const double j00 = dt_s * (ci * c - si * s), j01 = dt_s * (-ci * s - si * c);
  const double j10 = dt_s * (si * c + ci * s), j11 = dt_s * (-si * s + ci * c);
  const double ia = 1.0 / (e.a_m * e.a_m);
  const double ib = 1.0 / (e.b_m * e.b_m);
  const double h0 = p0.x_m * p0.x_m * ia + p0.y_m * p0.y_m * ib - 1.0;
  const double gx = 2.0 * p0.x_m * ia;  // dh/dp' at p0
  const double gy = 2.0 * p0.y_m * ib;
  // Linearised: h0 + g.(J v) >= (1 - delta) h_now  <=>  w . v >= rhs
  const double w0 = gx * j00 + gy * j10;
  const double w1 = gx * j01 + gy * j11;
  const double rhs = (1.0 - delta) * out.h_now - h0;
  auto clip = [&](double vx, double vy) {
    return std::array<double, 2>{std::clamp(vx, -limits.vx, limits.vx),
                                 std::clamp(vy, -limits.vy, limits.vy)};
  };
  std::array<double, 2> v = clip(u.vx, u.vy);
  auto lhs = [&](const std::array<double, 2>& q) { return w0 * q[0] + w1 * q[1]; };
  if (lhs(v) < rhs) {
    out.modified = true;
    // Dual: v(mu) = clip(u + mu w); w . v(mu) is non-decreasing in mu. Find the smallest mu >= 0
    // with w . v(mu) >= rhs (bisection to machine precision; 60 halvings).
    const double wn = std::max(std::hypot(w0, w1), 1e-12);
    double hi = (std::abs(rhs - lhs(v)) + 1.0) / (wn * wn) + 1.0;
    while (lhs(clip(u.vx + hi * w0, u.vy + hi * w1)) < rhs && hi < 1e12)
      hi *= 2.0;
    const std::array<double, 2> best_effort = clip(u.vx + hi * w0, u.vy + hi * w1);
    if (lhs(best_effort) < rhs) {
      out.feasible = false;
      v = best_effort;
    } else {
      double lo = 0.0;
      for (int i = 0; i < 60; ++i) {
        const double mid = 0.5 * (lo + hi);
        if (lhs(clip(u.vx + mid * w0, u.vy + mid * w1)) >= rhs) {
          hi = mid;
        } else {
          lo = mid;
        }
      }
      v = clip(u.vx + hi * w0, u.vy + hi * w1);
    }
  }
  out.u = Twist{v[0], v[1], std::clamp(u.wz, -limits.wz, limits.wz)};
  const Point2 next{robot.x_m + dt_s * (c * v[0] - s * v[1]),
                    robot.y_m + dt_s * (s * v[0] + c * v[1])};
  out.h_next = barrier(person_next, next, e);
  return out;
}

}  // namespace core
