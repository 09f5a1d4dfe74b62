#pragma once
// The one seam through which anything reads time or sleeps.
// Time is nanoseconds since the monotonic epoch (CLOCK_MONOTONIC on Linux, 0 on a SimClock).
#include <chrono>

namespace hal {

using Nanos = std::chrono::nanoseconds;

class Clock {
 public:
  virtual ~Clock() = default;

  // Monotonic time now.
  [[nodiscard]] virtual Nanos now() const = 0;

  // Sleeps until the absolute monotonic deadline. Returns false when woken early by interrupt()
  // (shutdown); true when the deadline has passed.
  virtual bool sleep_until(Nanos deadline) = 0;

  // Wakes every sleeper now and makes later sleeps return false at once (used to stop threads).
  virtual void interrupt() = 0;

  // Threads that sleep on this clock announce themselves (a simulated clock advances virtual
  // time only while every announced thread sleeps). No-ops on the real clock.
  virtual void attach_thread() {}
  virtual void detach_thread() {}
};

// RAII for attach_thread/detach_thread.
class ClockThreadGuard {
 public:
  explicit ClockThreadGuard(Clock& clock) : clock_(clock) { clock_.attach_thread(); }
  ~ClockThreadGuard() { clock_.detach_thread(); }
  ClockThreadGuard(const ClockThreadGuard&) = delete;
  ClockThreadGuard& operator=(const ClockThreadGuard&) = delete;

 private:
  Clock& clock_;
};

}  // namespace hal
