#pragma once
// First-order low-pass of a 2-D value sampled at irregular times:
//   y += (1 - exp(-dt / tau)) (x - y),
// exact for a value held over dt, so the result does not depend on the sampling rate. The
// first sample after construction or reset() passes through; tau <= 0 passes every sample
// through. Time is passed in (dt), never read.
#include <algorithm>
#include <cmath>

#include "core/geometry/pose2.hpp"

namespace core {

class LowPass2 {
 public:
  explicit LowPass2(double time_constant_s) : time_constant_s_(time_constant_s) {}

  Point2 update(const Point2& x, double dt_s) {
    if (!primed_ || time_constant_s_ <= 0.0) {
      y_ = x;
      primed_ = true;
      return y_;
    }
    const double k = 1.0 - std::exp(-std::max(dt_s, 0.0) / time_constant_s_);
    y_ = Point2{y_.x_m + k * (x.x_m - y_.x_m), y_.y_m + k * (x.y_m - y_.y_m)};
    return y_;
  }
  void reset() { primed_ = false; }
  [[nodiscard]] bool primed() const { return primed_; }

 private:
  double time_constant_s_;
  Point2 y_{};
  bool primed_ = false;
};

}  // namespace core
