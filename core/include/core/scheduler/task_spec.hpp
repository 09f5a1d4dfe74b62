#pragma once
// One row of a fixed-rate task table (the table itself lives in firmware/).
#include <cstdint>
#include <string_view>

#include "core/time.hpp"

namespace core {

struct TaskSpec {
  std::string_view name;
  uint32_t rate_hz;    // releases per second, exact
  uint32_t budget_us;  // expected worst-case run time on the Jetson; exceeding it is counted
  uint8_t group;       // rate group = thread in real-time mode (index into the group table)
  uint8_t priority;    // order among tasks due at the same instant in a group (higher first)
};

struct GroupSpec {
  std::string_view name;
  int fifo_priority;  // SCHED_FIFO priority of the group's thread (1..49)
};

// What a task is told each run (ros2_control's update(time, period)): components never read
// the clock themselves, so simulation and replay are exact.
struct Tick {
  Nanos now;      // start of this run
  Nanos period;   // time since the start of the previous run (nominal period on the first run)
  Nanos release;  // when this run was due
};

}  // namespace core
