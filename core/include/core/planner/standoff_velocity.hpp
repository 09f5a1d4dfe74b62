#pragma once
// The person's velocity that the speed standoff (InteractiveSpaceConfig::speed_standoff) reads:
// low-passed in odom, so that the robot's turning does not move it and the tracker's velocity
// noise (the standoff grows ~0.7 m per m/s at walking pace) does not move q^d at every
// selection; returned in base_link axes for InteractiveSpace::update. The daemon's policy task
// and the training environment both take it from here, so a policy is trained on the candidates
// the robot will offer it. Time is passed in, never read.
#include "core/geometry/pose2.hpp"
#include "core/planner/interactive_space.hpp"
#include "core/time.hpp"
#include "core/util/low_pass.hpp"

namespace core {

class StandoffVelocity {
 public:
  explicit StandoffVelocity(const InteractiveSpaceConfig& config)
      : on_(config.speed_standoff), filter_(config.speed_standoff_filter_s) {}

  // The velocity for InteractiveSpace::update: with the standoff on, `velocity_odom` low-passed
  // and turned into base_link; off, `velocity_base` (the same velocity, unfiltered) as it is.
  Point2 base(const Point2& velocity_odom, const Point2& velocity_base, const Pose2& robot_odom,
              Nanos now) {
    if (!on_) return velocity_base;
    return robot_odom.inverse().rotate(filter_.update(velocity_odom, now));
  }
  // No person: the next one starts the filter afresh.
  void reset() { filter_.reset(); }

 private:
  bool on_;
  LowPass2 filter_;
};

}  // namespace core
