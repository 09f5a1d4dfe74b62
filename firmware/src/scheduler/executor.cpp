#include "firmware/scheduler/executor.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <latch>
#include <numeric>

#include "hal/realtime.hpp"

namespace firmware {

Executor::Executor(hal::Clock& clock, std::span<const core::GroupSpec> groups,
                   std::vector<TaskBinding> tasks)
    : clock_(clock), groups_(groups.begin(), groups.end()), tasks_(std::move(tasks)) {
  for (const auto& t : tasks_) {
    stats_.push_back(std::make_unique<core::TaskStats>(
        core::Nanos(1'000'000'000 / std::max<uint32_t>(t.spec.rate_hz, 1)),
        std::chrono::microseconds(t.spec.budget_us)));
  }
}

Executor::~Executor() {
  stop();
}

size_t Executor::find(std::string_view name) const {
  for (size_t i = 0; i < tasks_.size(); ++i) {
    if (tasks_[i].spec.name == name) return i;
  }
  return tasks_.size();
}

void Executor::run_loop(std::span<const size_t> task_indices, core::Nanos origin) {
  // Fixed order among tasks due together: priority (higher first), then table order.
  std::vector<size_t> order(task_indices.begin(), task_indices.end());
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return tasks_[a].spec.priority > tasks_[b].spec.priority;
  });
  std::vector<core::ReleaseSchedule> schedules;
  schedules.reserve(order.size());
  for (const size_t i : order)
    schedules.emplace_back(tasks_[i].spec.rate_hz, origin);
  std::vector<core::Nanos> last_start(order.size(), core::Nanos(-1));

  while (!stop_requested()) {
    core::Nanos next = schedules[0].next_release();
    for (const auto& s : schedules)
      next = std::min(next, s.next_release());
    if (!clock_.sleep_until(next)) break;

    // Run what is due, best first; time moves while tasks run, so look again after each one.
    for (;;) {
      if (stop_requested()) return;
      const core::Nanos now = clock_.now();
      size_t pick = order.size();
      for (size_t k = 0; k < order.size(); ++k) {
        if (schedules[k].next_release() <= now) {
          pick = k;
          break;
        }
      }
      if (pick == order.size()) break;

      const size_t task = order[pick];
      const core::Nanos start = clock_.now();
      const core::ReleaseSchedule::Claim claim = schedules[pick].claim(start);
      const core::Nanos period = last_start[pick] < core::Nanos(0)
                                     ? schedules[pick].nominal_period()
                                     : start - last_start[pick];
      last_start[pick] = start;
      tasks_[task].fn(core::Tick{start, period, claim.release});
      const core::Nanos end = clock_.now();
      stats_[task]->record(core::TaskTiming{claim.first_due, claim.release, start, end,
                                            claim.following, claim.skipped});
    }
  }
}

void Executor::start(core::Nanos origin, bool realtime) {
  stop_.store(false, std::memory_order_release);
  std::vector<std::pair<size_t, std::vector<size_t>>> plan;  // group -> its tasks
  for (size_t g = 0; g < groups_.size(); ++g) {
    std::vector<size_t> members;
    for (size_t i = 0; i < tasks_.size(); ++i) {
      if (tasks_[i].spec.group == g) members.push_back(i);
    }
    if (!members.empty()) plan.emplace_back(g, std::move(members));
  }
  // spdlog's registry (the default logger) is created on first use; have that happen here, before
  // any task thread exists, not in whichever two threads log first (libspdlog is not built with
  // ThreadSanitizer, which then cannot see the static's guard and reports the first logs of the
  // task threads as a race).
  (void)spdlog::default_logger_raw();
  // Attach every thread before the first one exists, so a simulated clock cannot advance while
  // some group thread has not reached its first sleep yet.
  for (size_t k = 0; k < plan.size(); ++k)
    clock_.attach_thread();
  std::latch ready(static_cast<std::ptrdiff_t>(plan.size()));
  for (auto& [g, members] : plan) {
    threads_.emplace_back([this, g = g, members = std::move(members), origin, realtime, &ready] {
      const core::GroupSpec& group = groups_[g];
      hal::set_current_thread_name(std::string("cmp-") + std::string(group.name));
      if (realtime && group.fifo_priority > 0) {
        const hal::RtResult rt = hal::set_current_thread_fifo(group.fifo_priority);
        std::lock_guard lock(rt_mutex_);
        rt_outcomes_.push_back(RtOutcome{std::string(group.name), rt.ok, rt.message});
      }
      ready.count_down();
      run_loop(members, origin);
      clock_.detach_thread();
    });
  }
  ready.wait();
}

void Executor::run(core::Nanos origin) {
  std::vector<size_t> all(tasks_.size());
  std::iota(all.begin(), all.end(), size_t{0});
  const hal::ClockThreadGuard attached(clock_);  // a SimClock is idle only while we sleep
  run_loop(all, origin);
}

void Executor::stop() {
  stop_.store(true, std::memory_order_release);
  clock_.interrupt();
  for (auto& t : threads_) {
    if (t.joinable()) t.join();
  }
  threads_.clear();
}

std::vector<RtOutcome> Executor::rt_outcomes() const {
  std::lock_guard lock(rt_mutex_);
  return rt_outcomes_;
}

}  // namespace firmware
