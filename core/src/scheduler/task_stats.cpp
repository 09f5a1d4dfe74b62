#include "core/scheduler/task_stats.hpp"

namespace core {
namespace {
void bump(std::atomic<uint64_t>& c, uint64_t by = 1) {
  c.store(c.load(std::memory_order_relaxed) + by, std::memory_order_relaxed);
}
}  // namespace

void TaskStats::record(const TaskTiming& t) {
  const int64_t prev_start = last_start_ns_.load(std::memory_order_relaxed);
  if (prev_start >= 0 && t.skipped == 0) {
    const Nanos interval = t.start - Nanos(prev_start);
    period_jitter_.record(interval > period_ ? interval - period_ : period_ - interval);
  }
  start_latency_.record(t.start - t.due);
  const Nanos run = t.end - t.start;
  run_time_.record(run);
  if (run > budget_) bump(budget_exceeded_);
  if (t.end > t.deadline) bump(overruns_);
  if (t.skipped > 0) bump(skipped_, t.skipped);
  last_start_ns_.store(t.start.count(), std::memory_order_relaxed);
  bump(runs_);
  last_end_ns_.store(t.end.count(), std::memory_order_release);
}

}  // namespace core
