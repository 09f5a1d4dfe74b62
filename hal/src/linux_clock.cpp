#include "hal/linux_clock.hpp"

#include <cerrno>
#include <ctime>

namespace hal {
namespace {

timespec to_timespec(Nanos t) {
  const auto ns = t.count();
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(ns / 1'000'000'000);
  ts.tv_nsec = static_cast<long>(ns % 1'000'000'000);
  return ts;
}

}  // namespace

Nanos monotonic_now() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return Nanos(static_cast<int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec);
}

Nanos LinuxClock::now() const {
  return monotonic_now();
}

bool LinuxClock::sleep_until(Nanos deadline) {
  // Sleep in slices no longer than kMaxSleepSlice so a stop request is seen promptly; each slice
  // targets an absolute time, so slicing adds no drift.
  while (!interrupted_.load(std::memory_order_acquire)) {
    const Nanos now_ns = now();
    if (now_ns >= deadline) return true;
    const Nanos target = (deadline - now_ns > kMaxSleepSlice) ? now_ns + kMaxSleepSlice : deadline;
    const timespec ts = to_timespec(target);
    int rc = 0;
    do {
      rc = clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr);
    } while (rc == EINTR && !interrupted_.load(std::memory_order_acquire));
  }
  return false;
}

}  // namespace hal
