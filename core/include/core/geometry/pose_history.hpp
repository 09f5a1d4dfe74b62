#pragma once
// A short, fixed-capacity history of stamped poses (odom -> base_link from the base's
// odometry), to look up where the robot was when a measurement was taken. No allocation after
// construction.
#include <cstddef>
#include <optional>
#include <vector>

#include "core/geometry/body_velocity.hpp"
#include "core/geometry/pose2.hpp"
#include "core/time.hpp"

namespace core {

// `pose` moved on for `dt_s` at `velocity` (first order: the base's odometry comes every 20 ms).
[[nodiscard]] Pose2 carried(const Pose2& pose, const BodyVelocity& velocity, double dt_s);

class PoseHistory {
 public:
  // `max_extrapolation`: a query newer than the newest pose carries the newest pose on at its
  // velocity up to this far ahead (the base reports at 50 Hz, the tracker at 120 Hz: most
  // tracker frames are newer than the newest odometry); beyond it, no answer.
  PoseHistory(size_t capacity, Nanos max_extrapolation);

  // Stamps must increase; an older or equal stamp is ignored (returns false). `velocity`: the
  // body's at `pose` (zero: a newer query holds the pose).
  bool add(const Pose2& pose, Nanos stamp, const BodyVelocity& velocity = {});
  // Interpolated pose at `t`; nullopt when `t` is before the oldest pose kept, too far past the
  // newest, or the history is empty.
  [[nodiscard]] std::optional<Pose2> at(Nanos t) const;
  [[nodiscard]] size_t size() const { return size_; }
  [[nodiscard]] std::optional<Nanos> newest_stamp() const;

 private:
  struct Entry {
    Pose2 pose;
    Nanos stamp{0};
    BodyVelocity velocity;
  };
  [[nodiscard]] const Entry& entry(size_t i) const;  // 0 = oldest

  std::vector<Entry> ring_;
  size_t head_ = 0;  // next write
  size_t size_ = 0;
  Nanos max_extrapolation_;
};

}  // namespace core
