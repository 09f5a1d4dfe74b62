#pragma once
// CLOCK_MONOTONIC with clock_nanosleep(TIMER_ABSTIME): absolute deadlines, so periodic loops
// never accumulate drift, and EINTR simply re-sleeps to the same deadline.
#include <atomic>

#include "hal/clock.hpp"

namespace hal {

class LinuxClock final : public Clock {
 public:
  // Longest single sleep; bounds how long interrupt() takes to be noticed.
  static constexpr Nanos kMaxSleepSlice = std::chrono::milliseconds(50);

  [[nodiscard]] Nanos now() const override;
  bool sleep_until(Nanos deadline) override;
  void interrupt() override { interrupted_.store(true, std::memory_order_release); }

 private:
  std::atomic<bool> interrupted_{false};
};

// Monotonic now without a Clock object (for tools outside the scheduler).
Nanos monotonic_now();

}  // namespace hal
