#pragma once
// The safety supervisor's state machine (DESIGN.md section 5):
//   INIT -> ARMING -> ACTIVE <-> HOLD, and FAULT (latched until an operator clears it).
// Pure logic: every input arrives with its timestamp in SafetyInputs, time is an argument, no
// allocation. Only ACTIVE lets the controller's velocity through (see MotionGate).
#include <array>
#include <bitset>
#include <cstdint>
#include <limits>

#include "core/safety/debounce.hpp"
#include "core/safety/reason.hpp"
#include "core/time.hpp"

namespace core {

inline constexpr Nanos kNever = Nanos(std::numeric_limits<int64_t>::min());

enum class TrackerConfidence : uint8_t { kUnknown = 0, kGood = 1, kDegraded = 2, kBad = 3 };
const char* confidence_name(TrackerConfidence c);  // "GOOD", "DEGRADED", "BAD", "UNKNOWN"

// A snapshot of everything the supervisor judges, gathered by the supervisor task from the
// channels. Stamps are monotonic times of the latest data (kNever: nothing received yet).
struct SafetyInputs {
  bool initialized = false;  // daemon finished start-up (devices opened, tasks running)

  Nanos tracker_stamp = kNever;  // latest tracker frame that decoded
  TrackerConfidence tracker_confidence = TrackerConfidence::kUnknown;
  const char* tracker_detail = "";  // why (the gate's reason; static text), for the log line
  int tracker_quality = -1;         // effective quality 0..255 (-1: unknown)
  double person_distance_m = std::numeric_limits<double>::quiet_NaN();

  Nanos lidar_stamp = kNever;    // latest lidar packet decoded
  Nanos costmap_stamp = kNever;  // sensor time of the newest costmap

  Nanos base_feedback_stamp = kNever;  // latest Scout feedback frame
  uint16_t base_fault_word = 0;        // 0x211 fault bits that stop the base
  bool base_estop = false;
  bool rc_override = false;  // a person holds the remote control
  bool can_bus_off = false;
  uint64_t can_write_errors = 0;  // cumulative

  Nanos control_heartbeat = kNever;  // end of the latest control task run
  uint64_t control_overruns = 0;     // cumulative (scheduler statistics)
  bool numerical_failure = false;    // NaN/Inf seen in policy or controller

  bool operator_stop = false;
  bool shutdown = false;  // SIGTERM / SIGINT received
};

struct SupervisorConfig {
  Nanos arming_time = std::chrono::milliseconds(1000);   // all clear this long before ACTIVE
  Nanos resume_after = std::chrono::milliseconds(1000);  // a HOLD cause clear this long to resume
  Nanos tracker_timeout = std::chrono::milliseconds(100);
  Nanos tracker_confidence_recover = std::chrono::milliseconds(1000);
  // A companion that falls behind catches up: at 3 m the robot held while the person walked on,
  // and a lag of a second became a lost person (docs/EVALUATION.md). The tracker's own confidence
  // gate holds the robot where the signal degrades with range.
  double person_max_distance_m = 5.0;
  Nanos lidar_timeout = std::chrono::milliseconds(300);
  Nanos costmap_max_age = std::chrono::milliseconds(500);
  Nanos base_feedback_timeout = std::chrono::milliseconds(200);
  Nanos control_stall_timeout = std::chrono::milliseconds(100);
  // 'control overrun' holds the robot when this many control runs ended after their deadline
  // within the window. One late run leaves the base on the previous (barrier-checked) command for
  // a few more milliseconds; what the reason guards against is a controller that no longer keeps
  // its period. 1 holds on every single overrun (stricter; a VM's scheduling stalls then stop
  // the robot every few seconds: docs/PERFORMANCE.md). At most kMaxControlOverrunsToHold.
  uint32_t control_overruns_to_hold = 3;
  Nanos control_overrun_window = std::chrono::milliseconds(1000);
  // Which input families are supervised. A family with no device configured yet is still
  // supervised (and so holds the robot): disabling one is for bench tests only.
  bool require_tracker = true;
  bool require_lidar = true;
  bool require_base = true;
};

inline constexpr uint32_t kMaxControlOverrunsToHold = 16;

using ReasonSet = std::bitset<kReasonCount>;

struct Transition {
  SafetyState from;
  SafetyState to;
  Reason reason;                 // primary reason in the new state (kNone when ACTIVE)
  std::array<char, 200> values;  // the values that caused it, one line, NUL-terminated
};

struct SupervisorOutput {
  SafetyState state = SafetyState::kInit;
  Reason reason = Reason::kStarting;
  ReasonSet active;             // every cause present right now (debounced)
  bool motion_allowed = false;  // state == ACTIVE
  bool watchdog_ok = false;     // control task is making progress: ping systemd
  bool transitioned = false;    // state or primary reason changed in this update
  Transition transition{};      // valid when transitioned
};

class Supervisor {
 public:
  explicit Supervisor(const SupervisorConfig& config);

  SupervisorOutput update(const SafetyInputs& in, Nanos now);

  // Operator command: leaves FAULT (to ARMING) if no fault cause is present any more.
  // Returns false (and stays in FAULT) otherwise.
  bool request_fault_clear(const SafetyInputs& in, Nanos now);

  [[nodiscard]] SafetyState state() const { return state_; }
  [[nodiscard]] Reason reason() const { return reason_; }

 private:
  ReasonSet evaluate(const SafetyInputs& in, Nanos now);
  // Records the overruns new since the previous update at `now`; returns how many of the
  // recorded ones lie within the window (at most kMaxControlOverrunsToHold).
  uint32_t recent_overruns(uint64_t new_overruns, Nanos now);
  void describe(const SafetyInputs& in, Nanos now, Reason r, std::array<char, 200>& out) const;
  static Reason primary(const ReasonSet& set, Severity min_severity);

  SupervisorConfig config_;
  SafetyState state_ = SafetyState::kInit;
  Reason reason_ = Reason::kStarting;
  std::array<Debounce, kReasonCount> debounce_{};
  ReasonSet raw_;  // the conditions before hysteresis, at the latest update
  Nanos all_clear_since_ = kNever;
  uint64_t last_write_errors_ = 0;
  uint64_t last_overruns_ = 0;
  std::array<Nanos, kMaxControlOverrunsToHold> overrun_times_{};  // ring, newest at overrun_head_
  size_t overrun_head_ = 0;
  size_t overrun_count_ = 0;         // valid entries in the ring
  uint32_t overruns_in_window_ = 0;  // at the latest update, for the log line
  bool counters_seen_ = false;
};

}  // namespace core
