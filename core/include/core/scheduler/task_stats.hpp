#pragma once
// Per-task timing statistics, written by the one thread that runs the task and read by the
// reporter (status line, summary log, watchdog) without locks.
#include <atomic>
#include <cstdint>

#include "core/scheduler/release_schedule.hpp"
#include "core/util/histogram.hpp"

namespace core {

struct TaskTiming {
  Nanos due;         // the earliest release that was waiting for this run
  Nanos release;     // the release it serves (later than `due` when releases were skipped)
  Nanos start;       // when it began
  Nanos end;         // when it returned
  Nanos deadline;    // the next release
  uint64_t skipped;  // releases missed before this run
};

class TaskStats {
 public:
  TaskStats(Nanos nominal_period, Nanos budget) : period_(nominal_period), budget_(budget) {}

  void record(const TaskTiming& t);

  [[nodiscard]] uint64_t runs() const { return runs_.load(std::memory_order_relaxed); }
  // Run ended after the next release: the task ate into its next period.
  [[nodiscard]] uint64_t overruns() const { return overruns_.load(std::memory_order_relaxed); }
  // Releases that passed with no run at all.
  [[nodiscard]] uint64_t skipped() const { return skipped_.load(std::memory_order_relaxed); }
  // Run time above the table's budget_us (a warning sign before it becomes an overrun).
  [[nodiscard]] uint64_t budget_exceeded() const {
    return budget_exceeded_.load(std::memory_order_relaxed);
  }
  [[nodiscard]] Nanos last_end() const {
    return Nanos(last_end_ns_.load(std::memory_order_acquire));
  }
  [[nodiscard]] Nanos last_start() const {
    return Nanos(last_start_ns_.load(std::memory_order_relaxed));
  }

  // |actual start-to-start interval - nominal period|.
  [[nodiscard]] const DurationHistogram& period_jitter() const { return period_jitter_; }
  // start - due: how late the run began after the first release it was waiting for.
  [[nodiscard]] const DurationHistogram& start_latency() const { return start_latency_; }
  [[nodiscard]] const DurationHistogram& run_time() const { return run_time_; }
  [[nodiscard]] Nanos nominal_period() const { return period_; }
  [[nodiscard]] Nanos budget() const { return budget_; }

 private:
  Nanos period_;
  Nanos budget_;
  std::atomic<uint64_t> runs_{0};
  std::atomic<uint64_t> overruns_{0};
  std::atomic<uint64_t> skipped_{0};
  std::atomic<uint64_t> budget_exceeded_{0};
  std::atomic<int64_t> last_start_ns_{-1};
  std::atomic<int64_t> last_end_ns_{-1};
  DurationHistogram period_jitter_;
  DurationHistogram start_latency_;
  DurationHistogram run_time_;
};

}  // namespace core
