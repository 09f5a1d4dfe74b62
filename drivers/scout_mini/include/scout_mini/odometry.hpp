#pragma once
// odom -> base_link pose from the base's measured body velocities (0x221), pure.
// Mecanum: the lateral velocity is included. Each interval is integrated exactly for a constant
// body twist (SE(2) exponential), so a constant-speed arc stays on its circle.
#include "hal/clock.hpp"

namespace scout_mini {

struct Pose2D {
  double x_m = 0;
  double y_m = 0;
  double theta_rad = 0;  // wrapped to (-pi, pi]
};

class OdometryIntegrator {
 public:
  // Twist measured at `stamp`; each sample's twist is held until the next one (zero-order hold).
  // Gaps longer than `max_gap` are not integrated (the base was silent; the pose holds).
  void add(double vx_mps, double vy_mps, double wz_radps, hal::Nanos stamp);
  [[nodiscard]] const Pose2D& pose() const { return pose_; }
  [[nodiscard]] hal::Nanos stamp() const { return last_; }
  void reset(const Pose2D& p = {}) { pose_ = p; }

  hal::Nanos max_gap = std::chrono::milliseconds(200);

 private:
  Pose2D pose_;
  double vx_ = 0, vy_ = 0, wz_ = 0;
  hal::Nanos last_{0};
  bool has_last_ = false;
};

// Pure step: the pose after moving with body twist (vx, vy, wz) for dt seconds.
Pose2D integrate(const Pose2D& p, double vx, double vy, double wz, double dt);

}  // namespace scout_mini
