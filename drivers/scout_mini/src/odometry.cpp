#include "scout_mini/odometry.hpp"

#include <cmath>

namespace scout_mini {

Pose2D integrate(const Pose2D& p, double vx, double vy, double wz, double dt) {
  const double dth = wz * dt;
  // Body-frame displacement of a constant twist: V(dth) * [vx, vy] dt.
  double a = 1.0;  // sin(dth)/dth
  double b = 0.0;  // (1 - cos(dth))/dth
  if (std::abs(dth) > 1e-9) {
    a = std::sin(dth) / dth;
    b = (1.0 - std::cos(dth)) / dth;
  } else {
    b = dth / 2.0;
  }
  const double dx_body = (a * vx - b * vy) * dt;
  const double dy_body = (b * vx + a * vy) * dt;
  const double c = std::cos(p.theta_rad);
  const double s = std::sin(p.theta_rad);
  Pose2D out;
  out.x_m = p.x_m + c * dx_body - s * dy_body;
  out.y_m = p.y_m + s * dx_body + c * dy_body;
  out.theta_rad = std::remainder(p.theta_rad + dth, 2.0 * M_PI);
  return out;
}

void OdometryIntegrator::add(double vx, double vy, double wz, hal::Nanos stamp) {
  if (has_last_ && stamp > last_ && stamp - last_ <= max_gap) {
    const double dt = static_cast<double>((stamp - last_).count()) * 1e-9;
    pose_ = integrate(pose_, vx_, vy_, wz_, dt);
  }
  if (!has_last_ || stamp >= last_) {
    vx_ = vx;
    vy_ = vy;
    wz_ = wz;
    last_ = stamp;
    has_last_ = true;
  }
}

}  // namespace scout_mini
