#pragma once
// companiond's components and its task functions (bound to the task table). Tasks receive time
// through core::Tick and exchange data only through latest-value channels.
#include <atomic>
#include <cstdint>
#include <limits>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "amfitrack/amfitrack.hpp"
#include "amfitrack/person_frame.hpp"
#include "amfitrack/tap_link.hpp"
#include "core/channel/latest_value.hpp"
#include "core/channel/snapshot_channel.hpp"
#include "core/control/mppi.hpp"
#include "core/control/pid_follower.hpp"
#include "core/geometry/pose_history.hpp"
#include "core/human/human_ekf.hpp"
#include "core/perception/costmap.hpp"
#include "core/planner/goal_hold.hpp"
#include "core/planner/goal_slew.hpp"
#include "core/planner/interactive_space.hpp"
#include "core/planner/standoff_velocity.hpp"
#include "core/policy/mlp_policy.hpp"
#include "core/policy/observation.hpp"
#include "core/safety/motion_gate.hpp"
#include "core/safety/supervisor.hpp"
#include "firmware/config/daemon_config.hpp"
#include "firmware/lidar_pipeline.hpp"
#include "firmware/logging.hpp"
#include "firmware/scheduler/executor.hpp"
#include "hal/can/can_bus.hpp"
#include "hal/net/datagram_source.hpp"
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
  core::Pose2 odom;                             // odom -> base_link from the wheels
  core::Nanos odom_stamp = core::kNever;        // time of `odom`
};

// What the tracker task publishes: the gate's verdict and the link's health (the person's state
// itself travels as a core::HumanTrack).
struct TrackerHealth {
  core::Nanos frame_stamp = core::kNever;  // latest frame of the configured sensor
  core::TrackerConfidence confidence = core::TrackerConfidence::kUnknown;
  amfitrack::GateReason gate_reason = amfitrack::GateReason::kNoData;
  uint8_t quality = 0;  // effective (polarity applied)
  double person_distance_m = std::numeric_limits<double>::quiet_NaN();  // planar, base_link
  double rate_hz = 0;                                                   // measured frame rate
  bool link_up = false;
  uint64_t frames = 0;
  uint64_t dropped_frames = 0;   // frame-id gaps
  uint64_t decode_errors = 0;    // framing + payload
  uint64_t filter_rejected = 0;  // poses the human filter gated out
  uint64_t filter_resets = 0;
};

// What the lidar task publishes about the VLP-16 stream (the costmap travels as a snapshot).
struct LidarHealth {
  core::Nanos packet_stamp = core::kNever;   // latest data packet that decoded
  core::Nanos costmap_stamp = core::kNever;  // sensor time (scan end) of the newest costmap
  uint64_t packets = 0;
  uint64_t decode_errors = 0;
  uint64_t lost_packets = 0;
  uint64_t kernel_drops = 0;
  uint64_t scans = 0;
  size_t obstacle_cells = 0;
};

// What the policy task publishes: the companion point q^d and how it was chosen.
struct CompanionGoal {
  core::GoalStatus status = core::GoalStatus::kNoPerson;
  int index = -1;           // into W
  int points = 0;           // n
  size_t free_points = 0;   // |P|
  core::Pose2 goal_base;    // q^d in base_link at the time of the choice
  core::Pose2 goal_odom;    // the same in odom
  core::Pose2 person_odom;  // the person when q^d was chosen (q^d moves with them)
  // Static text: "objective", "policy", "fixed_behind", "fixed_side" (policy.selector).
  const char* selector = "objective";
  bool held = false;  // no free point: the last choice kept (policy.hold_last_point_ms)
  // q^d in the frame of the person it was chosen around: a point of their W, which moves with
  // them (the controller carries it along their predicted path).
  [[nodiscard]] core::Pose2 goal_in_person() const { return person_odom.inverse() * goal_odom; }
};
// What the control task publishes: how the controller did on its latest run.
struct ControlStatus {
  bool tracking = false;           // MPPI ran on a goal (else: holding / stopping)
  bool numerical_failure = false;  // latched: NaN/Inf from the controller at some run
  bool repaired = false;           // the QP repair changed the first control
  double min_cost = 0;             // the best rollout's cost
  core::MppiCostTerms best_cost;   // ... by term (why the robot leaves q^d: collision, barrier)
  double effective_samples = 0;
  uint64_t runs = 0;             // MPPI steps so far
  uint64_t failures = 0;         // MPPI steps that failed
  uint64_t repairs = 0;          // first controls the QP repair changed
  uint64_t closing_limits = 0;   // commands slowed toward the person (closing_speed.*)
  uint64_t obstacle_limits = 0;  // slowed to stop short of an obstacle (obstacle_speed.*)
  uint64_t guided_plans = 0;     // steps where a structured sample became the plan (guide_samples)
  uint64_t paths_planned = 0;    // steps with a costmap path round an obstacle (path_guide)
  uint64_t path_guided_plans = 0;   // ... where the path sample became the plan
  uint64_t orbits_planned = 0;      // steps with q^d across the person's ellipse (orbit_guide)
  uint64_t orbit_guided_plans = 0;  // ... where an orbit sample became the plan
  core::BodyVelocity command;       // after the supervisor's gate (what went to the base)
};

// "front", "left", "behind", "right" of the person, from the design point's angle.
const char* side_of_person(int index, int points);
// The eighth of the circle around the person (0 front, 2 left, 4 behind, 6 right; -1 none) of
// point `index` of n, and its name.
int side_sector(int index, int points);
const char* side_name(int sector);
core::ClosingSpeedConfig closing_speed_config(const DaemonConfig& cfg);
core::InteractiveSpaceConfig interactive_space_config(const DaemonConfig& cfg);
// The learned selector's weights named by policy.file, checked against this configuration (n,
// the observation layout). No file configured: no policy and no error.
core::PolicyLoadResult load_configured_policy(const DaemonConfig& cfg);
core::MppiConfig mppi_config(const DaemonConfig& cfg);
core::PidFollowerConfig pid_follower_config(const DaemonConfig& cfg);

core::SupervisorConfig supervisor_config(const DaemonConfig& cfg);
core::StopLimits stop_limits(const DaemonConfig& cfg);
amfitrack::AmfitrackConfig amfitrack_config(const DaemonConfig& cfg);
amfitrack::TrackerExtrinsics tracker_extrinsics(const DaemonConfig& cfg);
amfitrack::ReconnectConfig tracker_reconnect_config(const DaemonConfig& cfg);
core::HumanEkfConfig human_ekf_config(const DaemonConfig& cfg);
core::TrackerConfidence to_tracker_confidence(amfitrack::Confidence c);

// One instance per process: its members stay grouped by the task that owns them (below), not
// packed for size (34 bytes of padding).
class Daemon {  // NOLINT(clang-analyzer-optin.performance.Padding)
 public:
  Daemon(const DaemonConfig& cfg, hal::SystemdNotifier& notifier);

  // The task table bound to this daemon, for an Executor.
  std::vector<TaskBinding> bindings();
  // The Scout Mini's CAN link (optional: without it the supervisor holds, base feedback silent).
  // Must be called before the executor starts. The base and control tasks share the driver, so
  // they must be in one rate group: returns false (refuse to start) otherwise.
  bool attach_base(std::unique_ptr<hal::CanBus> bus);
  [[nodiscard]] const core::LatestValue<BaseHealth>& base_health() const { return base_health_; }
  // The Amfitrack link (optional: without it the supervisor holds, tracker silent). Must be
  // called before the executor starts.
  void attach_tracker(std::unique_ptr<amfitrack::PacketLink> link);
  [[nodiscard]] const core::LatestValue<TrackerHealth>& tracker_health() const {
    return tracker_health_;
  }
  [[nodiscard]] const core::LatestValue<core::HumanTrack>& human_track() const {
    return human_track_;
  }
  [[nodiscard]] const core::HumanEkfConfig& human_config() const { return human_config_; }
  // The VLP-16's data socket (optional: without it the supervisor holds, lidar silent).
  void attach_lidar(std::unique_ptr<hal::DatagramSource> data);
  [[nodiscard]] const core::LatestValue<LidarHealth>& lidar_health() const { return lidar_health_; }
  [[nodiscard]] const core::SnapshotChannel<core::Costmap>& costmap() const { return costmap_; }
  [[nodiscard]] const core::LatestValue<CompanionGoal>& goal() const { return goal_; }
  [[nodiscard]] const core::LatestValue<ControlStatus>& control_status() const {
    return control_status_;
  }
  // The learned selector (optional; without it the objective argmin selects). Before start.
  void attach_policy(core::PolicyFile policy);
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
  // Built by the report task; rates are measured over its last period. Any thread.
  [[nodiscard]] std::string status_line() const;
  // "tracker 120 base 50 ..." (Hz, measured by the report task). Any thread.
  [[nodiscard]] std::string rates_text() const;
  // The machine-readable status (JSON object), built by the report task. Any thread.
  [[nodiscard]] std::string status_json() const;
  // Where the report task writes status_json() (atomically, each run); empty: nowhere.
  // Before start.
  void set_status_file(std::string path) { status_file_ = std::move(path); }
  // Per-task timing summary (rate, jitter p50/p99/max, run time p99/max, overruns, skips).
  [[nodiscard]] std::string timing_summary() const;

 private:
  // One MPPI-CBF step toward the current goal; false when there is nothing to track.
  bool run_controller(core::Nanos now, core::BodyVelocity& requested);
  bool run_pid_follower(core::Nanos now, core::BodyVelocity& requested);
  std::string safety_text(const SafetySnapshot& s) const;
  std::string tracker_text(core::Nanos now) const;
  std::string lidar_text(core::Nanos now) const;

  DaemonConfig cfg_;
  hal::SystemdNotifier& notifier_;
  const Executor* executor_ = nullptr;
  const core::TaskStats* control_stats_ = nullptr;  // resolved once in attach()

  std::atomic<bool> initialized_{false};
  std::atomic<bool> shutdown_{false};
  // Since when the control task has commanded zero during shutdown (monotonic ns; max: not).
  std::atomic<int64_t> zero_commanded_since_ns_{std::numeric_limits<int64_t>::max()};

  // supervisor task state
  core::Supervisor supervisor_;
  core::Nanos initialized_at_ = core::kNever;
  core::Nanos last_watchdog_ping_ = core::kNever;
  std::optional<std::chrono::microseconds> watchdog_interval_;
  core::LatestValue<SafetySnapshot> safety_;

  // tracker (driver, extrinsics and filter owned by the tracker task)
  void tracker_link_events(core::Nanos now);
  std::unique_ptr<amfitrack::PacketLink> tracker_link_;
  std::unique_ptr<amfitrack::Amfitrack> tracker_;
  const amfitrack::ReconnectingLink* tracker_reconnecting_ = nullptr;  // tracker_link_, if so
  double person_distance_m_ = std::numeric_limits<double>::quiet_NaN();
  amfitrack::PersonFrame person_frame_;
  core::HumanEkfConfig human_config_;
  core::HumanEkf human_ekf_;
  core::PoseHistory odom_history_;
  bool tracker_link_was_up_ = false;
  uint64_t tracker_open_failures_seen_ = 0;
  RateLimitedLog tracker_warning_;
  core::LatestValue<TrackerHealth> tracker_health_;
  core::LatestValue<core::HumanTrack> human_track_;

  // lidar (socket and pipeline owned by the lidar task)
  std::unique_ptr<hal::DatagramSource> lidar_rx_;
  std::unique_ptr<LidarPipeline> lidar_;
  core::PoseHistory lidar_odom_;
  LidarHealth lidar_state_;
  RateLimitedLog lidar_warning_;
  core::LatestValue<LidarHealth> lidar_health_;
  core::SnapshotChannel<core::Costmap> costmap_;

  // policy task state
  core::InteractiveSpace space_;
  enum class Selector : uint8_t { kAuto, kObjective, kFixedBehind, kFixedSide };
  Selector selector_ = Selector::kAuto;  // policy.selector, resolved once
  std::unique_ptr<core::MlpPolicy> policy_;
  std::vector<float> observation_;
  // The person's velocity for interactive_space.speed_standoff; reset while there is no person.
  core::StandoffVelocity standoff_velocity_;
  core::GoalSlew goal_slew_;  // objective.slew_points_per_s
  core::GoalHold goal_hold_;  // policy.hold_last_point_ms; its index is the previous action
  core::LatestValue<CompanionGoal> goal_;

  // base (driver owned by the realtime group's thread: base and control tasks)
  std::unique_ptr<hal::CanBus> base_bus_;
  std::unique_ptr<scout_mini::ScoutMini> base_;
  core::LatestValue<BaseHealth> base_health_;

  // control task state
  core::Mppi mppi_;
  core::PidFollower pid_;
  bool use_pid_ = false;                   // control.controller: pid_follower (evaluation baseline)
  std::vector<core::Pose2> person_path_;   // the person's predicted poses at the MPPI steps
  std::vector<core::Pose2> goal_path_;     // q^d carried along the person's faded prediction
  std::vector<double> goal_heading_path_;  // q^d's heading alone (its own turn fading), rad
  core::Twist last_command_;               // the gate's previous output (MPPI's start control)
  ControlStatus control_state_;
  core::LatestValue<ControlStatus> control_status_;
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
  std::string rates_;
  std::string json_;
  std::string status_file_;
  bool status_file_warned_ = false;
  mutable std::mutex report_mutex_;  // status_, rates_, json_ (read by other threads)
  std::string build_status_json(core::Nanos now) const;
  void write_status_file();
};

}  // namespace firmware
