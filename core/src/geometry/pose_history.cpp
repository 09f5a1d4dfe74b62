#include "core/geometry/pose_history.hpp"

namespace core {

Pose2 carried(const Pose2& pose, const BodyVelocity& velocity, double dt_s) {
  return pose * Pose2{velocity.vx_mps * dt_s, velocity.vy_mps * dt_s, velocity.wz_radps * dt_s};
}

PoseHistory::PoseHistory(size_t capacity, Nanos max_extrapolation)
    : ring_(capacity == 0 ? 1 : capacity), max_extrapolation_(max_extrapolation) {}

const PoseHistory::Entry& PoseHistory::entry(size_t i) const {
  return ring_[(head_ + ring_.size() - size_ + i) % ring_.size()];
}

bool PoseHistory::add(const Pose2& pose, Nanos stamp, const BodyVelocity& velocity) {
  if (size_ > 0 && stamp <= entry(size_ - 1).stamp) return false;
  ring_[head_] = Entry{pose, stamp, velocity};
  head_ = (head_ + 1) % ring_.size();
  if (size_ < ring_.size()) ++size_;
  return true;
}

std::optional<Nanos> PoseHistory::newest_stamp() const {
  if (size_ == 0) return std::nullopt;
  return entry(size_ - 1).stamp;
}

std::optional<Pose2> PoseHistory::at(Nanos t) const {
  if (size_ == 0) return std::nullopt;
  const Entry& newest = entry(size_ - 1);
  if (t >= newest.stamp) {
    if (t - newest.stamp > max_extrapolation_) return std::nullopt;
    return carried(newest.pose, newest.velocity, to_seconds(t - newest.stamp));
  }
  if (t < entry(0).stamp) return std::nullopt;
  // Binary search for the first entry after t.
  size_t lo = 0;
  size_t hi = size_ - 1;
  while (lo + 1 < hi) {
    const size_t mid = (lo + hi) / 2;
    if (entry(mid).stamp <= t) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  const Entry& a = entry(lo);
  const Entry& b = entry(hi);
  const double s =
      static_cast<double>((t - a.stamp).count()) / static_cast<double>((b.stamp - a.stamp).count());
  return interpolate(a.pose, b.pose, s);
}

}  // namespace core
