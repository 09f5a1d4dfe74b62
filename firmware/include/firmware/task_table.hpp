#pragma once
// THE task table of companiond: every rate, time budget and priority in the program, and
// nowhere else (ArduPilot's SCHED_TASK style).
#include <array>
#include <string_view>

#include "core/scheduler/task_spec.hpp"

namespace firmware {

class Daemon;
using DaemonTaskFn = void (Daemon::*)(const core::Tick&);

struct TaskRow {
  core::TaskSpec spec;
  DaemonTaskFn fn;
  // Empty when the task does its real job; otherwise what it is still waiting for. Shown in the
  // status so nobody mistakes an empty shell for work.
  std::string_view pending;
};

// Rate groups: one thread each in real-time mode.
enum Group : uint8_t {
  kGroupRealtime = 0,
  kGroupPlanning = 1,
  kGroupPerception = 2,
  kGroupReport = 3
};

const std::array<core::GroupSpec, 4>& group_table();
const std::array<TaskRow, 8>& task_table();

}  // namespace firmware
