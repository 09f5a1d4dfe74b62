#pragma once
// Absolute release times of a fixed-rate task: release_k = origin + k * 1 s / rate_hz, computed
// exactly in integers from the origin (never by adding a rounded period), so a 120 Hz task
// releases exactly 120 times per second forever: no drift.
#include <cstdint>

#include "core/time.hpp"

namespace core {

class ReleaseSchedule {
 public:
  ReleaseSchedule(uint32_t rate_hz, Nanos origin);

  [[nodiscard]] Nanos next_release() const { return release_at(next_k_); }
  [[nodiscard]] Nanos nominal_period() const { return Nanos(1'000'000'000 / rate_hz_); }
  [[nodiscard]] uint32_t rate_hz() const { return rate_hz_; }

  struct Claim {
    Nanos first_due;   // the earliest release that was pending (lateness is measured from it)
    Nanos release;     // the release this run serves (latest release <= start)
    uint64_t skipped;  // releases that passed without a run (the task was late)
    Nanos following;   // the release after this run: its deadline
  };
  // Called at the start of a run (start >= next_release()). Serves the latest due release and
  // skips the older ones, so a late task catches up by skipping, never by bursting.
  Claim claim(Nanos start);

  [[nodiscard]] Nanos release_at(uint64_t k) const;

 private:
  uint32_t rate_hz_;
  Nanos origin_;
  uint64_t next_k_ = 0;
};

}  // namespace core
