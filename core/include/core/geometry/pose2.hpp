#pragma once
// Planar rigid transforms (SE(2)), REP-103 axes: x forward, y left, theta counter-clockwise.
// A Pose2 named a_in_b maps points from frame a to frame b: p_b = a_in_b * p_a.
#include <cmath>
#include <numbers>

namespace core {

// Wraps to (-pi, pi].
inline double wrap_angle(double a) {
  a = std::remainder(a, 2.0 * std::numbers::pi);
  return a <= -std::numbers::pi ? a + 2.0 * std::numbers::pi : a;
}

struct Point2 {
  double x_m = 0;
  double y_m = 0;
};

struct Pose2 {
  double x_m = 0;
  double y_m = 0;
  double theta_rad = 0;

  [[nodiscard]] Point2 apply(const Point2& p) const {
    const double c = std::cos(theta_rad);
    const double s = std::sin(theta_rad);
    return {x_m + c * p.x_m - s * p.y_m, y_m + s * p.x_m + c * p.y_m};
  }
  // Rotation only (for velocities and directions).
  [[nodiscard]] Point2 rotate(const Point2& v) const {
    const double c = std::cos(theta_rad);
    const double s = std::sin(theta_rad);
    return {c * v.x_m - s * v.y_m, s * v.x_m + c * v.y_m};
  }
  [[nodiscard]] Pose2 inverse() const {
    const double c = std::cos(theta_rad);
    const double s = std::sin(theta_rad);
    return {-c * x_m - s * y_m, s * x_m - c * y_m, wrap_angle(-theta_rad)};
  }
  // (*this) * b: b expressed in this pose's parent frame.
  [[nodiscard]] Pose2 operator*(const Pose2& b) const {
    const Point2 t = apply({b.x_m, b.y_m});
    return {t.x_m, t.y_m, wrap_angle(theta_rad + b.theta_rad)};
  }
};

// Linear in position, shortest way in angle; s in [0, 1].
inline Pose2 interpolate(const Pose2& a, const Pose2& b, double s) {
  return {a.x_m + s * (b.x_m - a.x_m), a.y_m + s * (b.y_m - a.y_m),
          wrap_angle(a.theta_rad + s * wrap_angle(b.theta_rad - a.theta_rad))};
}

}  // namespace core
