#pragma once
// Runs a fixed-rate task table on a hal::Clock.
//
// Threaded mode: one thread per rate group (SCHED_FIFO at the group's priority when permitted),
// so a long 10 Hz task on its own group cannot delay the 100 Hz group.
// Single-thread mode: every task on the calling thread, in a fixed order: with a SimClock this
// is the deterministic mode of simulation, replay and tests (same inputs, same outputs).
//
// Each group sleeps to the earliest absolute release of its tasks, runs every task that is due
// (highest priority first) and records release/start/end in the task's statistics.
#include <atomic>
#include <functional>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "core/scheduler/release_schedule.hpp"
#include "core/scheduler/task_spec.hpp"
#include "core/scheduler/task_stats.hpp"
#include "hal/clock.hpp"

namespace firmware {

using TaskFn = std::function<void(const core::Tick&)>;

struct TaskBinding {
  core::TaskSpec spec;
  TaskFn fn;
};

struct RtOutcome {
  std::string group;
  bool ok = false;
  std::string message;
};

class Executor {
 public:
  Executor(hal::Clock& clock, std::span<const core::GroupSpec> groups,
           std::vector<TaskBinding> tasks);
  ~Executor();
  Executor(const Executor&) = delete;
  Executor& operator=(const Executor&) = delete;

  // Threaded mode: starts one thread per group whose first releases are at `origin`, and returns
  // once every thread has tried its real-time priority (see rt_outcomes()).
  void start(core::Nanos origin, bool realtime);
  // Single-thread mode: runs on the calling thread until stop() (from a task or another thread).
  void run(core::Nanos origin);
  // Asks every loop to finish after its current task, wakes sleepers and joins threads.
  void stop();
  [[nodiscard]] bool stop_requested() const { return stop_.load(std::memory_order_acquire); }

  [[nodiscard]] std::vector<RtOutcome> rt_outcomes() const;
  [[nodiscard]] size_t task_count() const { return tasks_.size(); }
  [[nodiscard]] const core::TaskSpec& spec(size_t i) const { return tasks_[i].spec; }
  [[nodiscard]] const core::TaskStats& stats(size_t i) const { return *stats_[i]; }
  // Index of the task called `name`, or task_count().
  [[nodiscard]] size_t find(std::string_view name) const;

 private:
  void run_loop(std::span<const size_t> task_indices, core::Nanos origin);

  hal::Clock& clock_;
  std::vector<core::GroupSpec> groups_;
  std::vector<TaskBinding> tasks_;
  std::vector<std::unique_ptr<core::TaskStats>> stats_;
  std::atomic<bool> stop_{false};
  std::vector<std::thread> threads_;
  mutable std::mutex rt_mutex_;
  std::vector<RtOutcome> rt_outcomes_;
};

}  // namespace firmware
