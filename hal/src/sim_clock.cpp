#include "hal/sim_clock.hpp"

namespace hal {

Nanos SimClock::now() const {
  std::lock_guard lock(mutex_);
  return now_;
}

void SimClock::set_now_locked(Nanos t) {
  if (t <= now_) return;
  now_ = t;
  // Release every sleeper that is due: they stop counting as asleep from this instant, before
  // their threads are even scheduled, so nobody can advance time past them meanwhile.
  pending_.erase(pending_.begin(), pending_.upper_bound(now_));
  cv_.notify_all();
}

void SimClock::maybe_advance_locked() {
  // Free running: everyone attached is asleep, so nothing can happen before the next deadline.
  while (!interrupted_ && !pending_.empty() &&
         static_cast<int>(pending_.size()) >= std::max(attached_, 1)) {
    const Nanos next = std::min(*pending_.begin(), horizon_);
    if (next <= now_) break;  // at the horizon: wait for the test to move it
    set_now_locked(next);
  }
  cv_.notify_all();  // wake wait_until_idle_at() observers
}

bool SimClock::sleep_until(Nanos deadline) {
  std::unique_lock lock(mutex_);
  if (interrupted_) return false;
  if (deadline <= now_) return true;
  pending_.insert(deadline);
  maybe_advance_locked();
  cv_.wait(lock, [&] { return interrupted_ || now_ >= deadline; });
  if (now_ < deadline) {
    // Interrupted: remove our own pending entry.
    const auto it = pending_.find(deadline);
    if (it != pending_.end()) pending_.erase(it);
    return false;
  }
  return true;
}

void SimClock::interrupt() {
  std::lock_guard lock(mutex_);
  interrupted_ = true;
  cv_.notify_all();
}

void SimClock::attach_thread() {
  std::lock_guard lock(mutex_);
  ++attached_;
}

void SimClock::detach_thread() {
  std::lock_guard lock(mutex_);
  --attached_;
  maybe_advance_locked();
}

void SimClock::advance_to(Nanos t) {
  std::lock_guard lock(mutex_);
  set_now_locked(t);
}

void SimClock::set_horizon(Nanos horizon) {
  std::lock_guard lock(mutex_);
  horizon_ = horizon;
  maybe_advance_locked();
}

bool SimClock::wait_until_idle_at(Nanos t) {
  std::unique_lock lock(mutex_);
  cv_.wait(lock, [&] {
    return interrupted_ || (now_ >= t && static_cast<int>(pending_.size()) >= attached_);
  });
  return !interrupted_;
}

size_t SimClock::sleepers() const {
  std::lock_guard lock(mutex_);
  return pending_.size();
}

}  // namespace hal
