#pragma once
// A body's velocity in its own frame (base_link): what the base is commanded and reports, and
// what carries its odometry on between reports.

namespace core {

struct BodyVelocity {
  double vx_mps = 0.0;    // forward
  double vy_mps = 0.0;    // left
  double wz_radps = 0.0;  // counter-clockwise
  [[nodiscard]] bool is_zero() const { return vx_mps == 0.0 && vy_mps == 0.0 && wz_radps == 0.0; }
};

}  // namespace core
