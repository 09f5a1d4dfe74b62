#pragma once
// The last thing between the controller and the base. In ACTIVE the requested body velocity
// passes; in every other state the output is a controlled stop: the previous output decelerates
// toward zero within the base's limits (never speeding up, never reversing) and is exactly zero
// no later than `max_stop_time` after motion stopped being allowed.
#include <cstdint>

#include "core/geometry/body_velocity.hpp"
#include "core/time.hpp"

namespace core {

struct StopLimits {
  double linear_decel_mps2 = 1.5;
  double angular_decel_radps2 = 3.0;
  Nanos max_stop_time = std::chrono::milliseconds(1000);
};

class MotionGate {
 public:
  explicit MotionGate(const StopLimits& limits) : limits_(limits) {}

  // `requested` is only used when motion_allowed. Non-finite requests are refused (stop) and
  // counted.
  BodyVelocity update(bool motion_allowed, const BodyVelocity& requested, Nanos now);

  [[nodiscard]] uint64_t rejected_non_finite() const { return rejected_non_finite_; }
  [[nodiscard]] bool stopping() const { return stopping_; }
  [[nodiscard]] const BodyVelocity& last_output() const { return last_; }

 private:
  StopLimits limits_;
  BodyVelocity last_{};
  Nanos last_time_{0};
  bool has_last_time_ = false;
  bool stopping_ = false;
  Nanos stop_started_{0};
  uint64_t rejected_non_finite_ = 0;
};

}  // namespace core
