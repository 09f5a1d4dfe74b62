#pragma once
// First-order low-pass of a 2-D value sampled at irregular times:
//   y += (1 - exp(-dt / tau)) (x - y),  dt = the time since the previous sample,
// exact for a value held over dt, so the result does not depend on the sampling rate. The
// first sample after construction or reset() passes through; tau <= 0 passes every sample
// through; a sample stamped before the previous one changes nothing. Time is passed in, never
// read.
#include <algorithm>
#include <cmath>

#include "core/geometry/pose2.hpp"
#include "core/time.hpp"

namespace core {

class LowPass2 {
 public:
  explicit LowPass2(double time_constant_s) : time_constant_s_(time_constant_s) {}

  Point2 update(const Point2& x, Nanos now) {
    if (!primed_ || time_constant_s_ <= 0.0) {
      y_ = x;
      primed_ = true;
      last_ = now;
      return y_;
    }
    const double dt_s = std::max(to_seconds(now - last_), 0.0);
    last_ = std::max(last_, now);
    const double k = 1.0 - std::exp(-dt_s / time_constant_s_);
    y_ = Point2{y_.x_m + k * (x.x_m - y_.x_m), y_.y_m + k * (x.y_m - y_.y_m)};
    return y_;
  }
  void reset() { primed_ = false; }
  [[nodiscard]] bool primed() const { return primed_; }

 private:
  double time_constant_s_;
  Point2 y_{};
  Nanos last_{0};
  bool primed_ = false;
};

}  // namespace core
