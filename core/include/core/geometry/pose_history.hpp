#pragma once
// A short, fixed-capacity history of stamped poses (odom -> base_link from the base's
// odometry), to look up where the robot was when a measurement was taken. No allocation after
// construction.
#include <cstddef>
#include <optional>
#include <vector>

#include "core/geometry/pose2.hpp"
#include "core/time.hpp"

namespace core {

class PoseHistory {
 public:
  // `max_extrapolation`: a query newer than the newest pose holds the newest pose up to this
  // far ahead (the base reports at 50 Hz, the tracker at 120 Hz); beyond it, no answer.
  PoseHistory(size_t capacity, Nanos max_extrapolation);

  // Stamps must increase; an older or equal stamp is ignored (returns false).
  bool add(const Pose2& pose, Nanos stamp);
  // Interpolated pose at `t`; nullopt when `t` is before the oldest pose kept, too far past the
  // newest, or the history is empty.
  [[nodiscard]] std::optional<Pose2> at(Nanos t) const;
  [[nodiscard]] size_t size() const { return size_; }
  [[nodiscard]] std::optional<Nanos> newest_stamp() const;

 private:
  struct Entry {
    Pose2 pose;
    Nanos stamp{0};
  };
  [[nodiscard]] const Entry& entry(size_t i) const;  // 0 = oldest

  std::vector<Entry> ring_;
  size_t head_ = 0;  // next write
  size_t size_ = 0;
  Nanos max_extrapolation_;
};

}  // namespace core
