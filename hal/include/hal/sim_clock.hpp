#pragma once
// Simulated (virtual) monotonic clock for simulation, replay and tests.
//
// Time advances only when told, in one of two ways:
//  - advance_to()/advance_by(): explicit steps from a test;
//  - free running: when every attached thread is asleep in sleep_until(), time jumps to the
//    earliest pending deadline (never beyond the horizon). With a single thread this is a
//    discrete-event loop; with several threads (one per rate group) it keeps their relative
//    timing exact: a thread that "works" for 80 ms does so by sleeping 80 ms of virtual time, and
//    the other threads keep running at their own deadlines meanwhile.
#include <condition_variable>
#include <limits>
#include <mutex>
#include <set>

#include "hal/clock.hpp"

namespace hal {

class SimClock final : public Clock {
 public:
  explicit SimClock(Nanos start = Nanos(0)) : now_(start) {}

  [[nodiscard]] Nanos now() const override;
  bool sleep_until(Nanos deadline) override;
  void interrupt() override;
  void attach_thread() override;
  void detach_thread() override;

  // Explicit stepping (monotonic: earlier times are ignored). Wakes sleepers that are due.
  void advance_to(Nanos t);
  void advance_by(Nanos d) { advance_to(now() + d); }

  // Free-running time never passes the horizon (default: unbounded).
  void set_horizon(Nanos horizon);

  // Blocks the caller (not an attached thread) until virtual time has reached `t` and every
  // attached thread sleeps. Returns false if interrupted first.
  bool wait_until_idle_at(Nanos t);

  // Number of sleep_until() calls that are waiting right now (diagnostics, tests).
  [[nodiscard]] size_t sleepers() const;

 private:
  void maybe_advance_locked();
  void set_now_locked(Nanos t);

  mutable std::mutex mutex_;
  std::condition_variable cv_;
  Nanos now_;
  Nanos horizon_{Nanos(std::numeric_limits<int64_t>::max())};
  std::multiset<Nanos> pending_;  // deadlines of sleepers not yet released
  int attached_ = 0;
  bool interrupted_ = false;
};

}  // namespace hal
