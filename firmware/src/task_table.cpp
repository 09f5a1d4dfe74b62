#include "firmware/task_table.hpp"

#include "firmware/daemon.hpp"

namespace firmware {

const std::array<core::GroupSpec, 4>& group_table() {
  // SCHED_FIFO priorities, all below 50 (the kernel's threaded IRQ handlers).
  static constexpr std::array<core::GroupSpec, 4> kGroups{{
      {"realtime", 45},    // inputs at their rates, supervisor, 100 Hz control
      {"planning", 35},    // 30 Hz companion-point selection
      {"perception", 25},  // 10 Hz lidar: long runs must never delay the groups above
      {"report", 0},       // status and summaries: not real-time (priority 0 = SCHED_OTHER)
  }};
  return kGroups;
}

// COMPANION_TASK(name, rate_hz, budget_us, group, priority, pending)
//   priority orders tasks due at the same instant within a group (and in single-thread mode):
//   fresh inputs first, then the supervisor's judgement, then the control output it gates.
#define COMPANION_TASK(name, rate_hz, budget_us, group, priority, pending)                    \
  TaskRow {                                                                                   \
    core::TaskSpec{#name, rate_hz, budget_us, group, priority}, &Daemon::name##_task, pending \
  }

const std::array<TaskRow, 8>& task_table() {
  static const std::array<TaskRow, 8> kTable{{
      COMPANION_TASK(tracker, 120, 300, kGroupRealtime, 90, ""),
      COMPANION_TASK(base, 50, 200, kGroupRealtime, 80, ""),
      COMPANION_TASK(supervisor, 100, 50, kGroupRealtime, 70, ""),
      COMPANION_TASK(control, 100, 3000, kGroupRealtime, 60, ""),
      COMPANION_TASK(policy, 30, 500, kGroupPlanning, 50, ""),
      COMPANION_TASK(lidar, 10, 5000, kGroupPerception, 40, ""),
      COMPANION_TASK(notify, 10, 200, kGroupReport, 20, ""),  // systemd watchdog pings
      COMPANION_TASK(report, 1, 2000, kGroupReport, 10, ""),  // status line, summaries
  }};
  return kTable;
}

#undef COMPANION_TASK

}  // namespace firmware
