#pragma once
// Real-time set-up of the process and of scheduler threads. Errors are values: the caller
// decides whether lacking RT is a warning or a refusal to start (config realtime.require).
#include <string>

namespace hal {

struct RtResult {
  bool ok = false;
  int error_number = 0;  // errno when !ok
  std::string message;   // human-readable, names the likely cause
};

// mlockall(MCL_CURRENT | MCL_FUTURE): no page faults on the hot path after start-up.
RtResult lock_process_memory();

// SCHED_FIFO at `priority` (1..49: below the kernel's threaded IRQ handlers at 50) for the
// calling thread.
RtResult set_current_thread_fifo(int priority);

// Names the calling thread (visible in top -H, ps -L, gdb); truncated to 15 characters.
void set_current_thread_name(const std::string& name);

}  // namespace hal
