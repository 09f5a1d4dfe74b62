#include "core/scheduler/release_schedule.hpp"

#include <algorithm>

namespace core {

namespace {
constexpr uint64_t kNsPerS = 1'000'000'000;
}

ReleaseSchedule::ReleaseSchedule(uint32_t rate_hz, Nanos origin)
    : rate_hz_(std::max<uint32_t>(rate_hz, 1)), origin_(origin) {}

Nanos ReleaseSchedule::release_at(uint64_t k) const {
  // k * 1e9 / rate without overflow: split k into whole seconds and the remainder.
  const uint64_t whole = k / rate_hz_;
  const uint64_t rem = k % rate_hz_;
  return origin_ + Nanos(static_cast<int64_t>(whole * kNsPerS + rem * kNsPerS / rate_hz_));
}

ReleaseSchedule::Claim ReleaseSchedule::claim(Nanos start) {
  uint64_t k = next_k_;
  if (start > origin_) {
    // Latest k with release_at(k) <= start; the division gives it to within one.
    const auto elapsed = static_cast<uint64_t>((start - origin_).count());
    const uint64_t whole_s = elapsed / kNsPerS;
    const uint64_t rem_ns = elapsed % kNsPerS;
    uint64_t estimate = whole_s * rate_hz_ + rem_ns * rate_hz_ / kNsPerS;
    while (estimate > 0 && release_at(estimate) > start)
      --estimate;
    while (release_at(estimate + 1) <= start)
      ++estimate;
    k = std::max(k, estimate);
  }
  Claim c{release_at(next_k_), release_at(k), k - next_k_, release_at(k + 1)};
  next_k_ = k + 1;
  return c;
}

}  // namespace core
