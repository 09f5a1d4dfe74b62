#pragma once
// companiond's components and its task functions (bound to the task table). Tasks receive time
// through core::Tick and exchange data only through latest-value channels.
#include <atomic>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "core/channel/latest_value.hpp"
#include "core/safety/motion_gate.hpp"
#include "core/safety/supervisor.hpp"
#include "firmware/config/daemon_config.hpp"
#include "firmware/logging.hpp"
#include "firmware/scheduler/executor.hpp"
#include "hal/can/can_bus.hpp"
#include "hal/sd_notify.hpp"
#include "scout_mini/scout_mini.hpp"

namespace firmware {

// What the supervisor task publishes for the others.
struct SafetySnapshot {
  core::SafetyState state = core::SafetyState::kInit;
  core::Reason reason = core::Reason::kStarting;
  bool motion_allowed = false;
  bool watchdog_ok = false;  // the control task makes progress: systemd may be pinged
  uint32_t active_mask = 0;  // bit i = kReasonTable[i] present
};
static_assert(core::kReasonCount <= 32, "active_mask holds one bit per reason");

// What the base task publishes about the Scout Mini for the supervisor and the status.
struct BaseHealth {
  core::Nanos feedback_stamp = core::kNever;  // latest 0x211/0x221
  uint16_t stopping_faults = 0;
  uint16_t fault_word = 0;
  bool estop = false;
  bool rc_override = false;
  bool bus_off = false;
  bool can_mode = false;
  uint64_t write_errors = 0;
  double vx_mps = 0, vy_mps = 0, wz_radps = 0;  // measured
};

core::SupervisorConfig supervisor_config(const DaemonConfig& cfg);
core::StopLimits stop_limits(const DaemonConfig& cfg);

class Daemon {
 public:
  Daemon(const DaemonConfig& cfg, hal::SystemdNotifier& notifier);

  // The task table bound to this daemon, for an Executor.
  std::vector<TaskBinding> bindings();
  // The Scout Mini's CAN link (optional: without it the supervisor holds, base feedback silent).
  // Must be called before the executor starts. The base and control tasks share the driver, so
  // they must be in one rate group: returns false (refuse to start) otherwise.
  bool attach_base(std::unique_ptr<hal::CanBus> bus);
  [[nodiscard]] const core::LatestValue<BaseHealth>& base_health() const { return base_health_; }
  // The executor running the bindings (the supervisor and the report read its statistics).
  void attach(const Executor& executor);

  // Start-up finished: devices open, tasks running (the supervisor leaves INIT).
  void mark_initialized() { initialized_.store(true, std::memory_order_release); }
  // SIGTERM/SIGINT: hold and stop the robot; shutdown_complete() tells when it is safe to exit.
  void request_shutdown() { shutdown_.store(true, std::memory_order_release); }
  [[nodiscard]] bool shutdown_complete() const;

  // The task functions (see task_table.cpp).
  void tracker_task(const core::Tick& tick);
  void base_task(const core::Tick& tick);
  void lidar_task(const core::Tick& tick);
  void policy_task(const core::Tick& tick);
  void control_task(const core::Tick& tick);
  void supervisor_task(const core::Tick& tick);
  void report_task(const core::Tick& tick);
  void notify_task(const core::Tick& tick);

  // Channels (read side), for tools and tests.
  [[nodiscard]] const core::LatestValue<SafetySnapshot>& safety() const { return safety_; }
  [[nodiscard]] const core::LatestValue<core::BodyVelocity>& command() const { return command_; }

  // One line: "HOLD: tracker silent (+2: ...) | tracker 120.0Hz ... | shells: ...".
  // Built by the report task; rates are measured over its last period.
  [[nodiscard]] std::string status_line() const;
  // Per-task timing summary (rate, jitter p50/p99/max, run time p99/max, overruns, skips).
  [[nodiscard]] std::string timing_summary() const;

 private:
  std::string safety_text(const SafetySnapshot& s) const;

  DaemonConfig cfg_;
  hal::SystemdNotifier& notifier_;
  const Executor* executor_ = nullptr;
  const core::TaskStats* control_stats_ = nullptr;  // resolved once in attach()

  std::atomic<bool> initialized_{false};
  std::atomic<bool> shutdown_{false};
  // When the supervisor first saw the shutdown request (monotonic ns; max until then).
  std::atomic<int64_t> shutdown_seen_at_ns_{std::numeric_limits<int64_t>::max()};

  // supervisor task state
  core::Supervisor supervisor_;
  core::Nanos initialized_at_ = core::kNever;
  core::Nanos last_watchdog_ping_ = core::kNever;
  std::optional<std::chrono::microseconds> watchdog_interval_;
  core::LatestValue<SafetySnapshot> safety_;

  // base (driver owned by the realtime group's thread: base and control tasks)
  std::unique_ptr<hal::CanBus> base_bus_;
  std::unique_ptr<scout_mini::ScoutMini> base_;
  core::LatestValue<BaseHealth> base_health_;

  // control task state
  core::MotionGate gate_;
  RateLimitedLog base_send_warning_;
  core::LatestValue<core::BodyVelocity> command_;

  // report task state
  std::vector<uint64_t> last_runs_;
  std::vector<core::Nanos> last_starts_;
  core::Nanos last_summary_ = core::kNever;
  std::vector<double> measured_rate_hz_;
  std::string status_;
  std::string last_status_sent_;
};

}  // namespace firmware
