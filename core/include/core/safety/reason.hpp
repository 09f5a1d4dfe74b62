#pragma once
// Stable reason codes of the safety supervisor (DESIGN.md section 5). The numbers are part of
// the interface (logs, status, diagnostics tools): never renumber, only add.
#include <array>
#include <cstdint>
#include <string_view>

namespace core {

enum class SafetyState : uint8_t { kInit = 0, kArming = 1, kActive = 2, kHold = 3, kFault = 4 };

enum class Reason : uint16_t {
  kNone = 0,
  kStarting = 1,
  kTrackerConfidenceLow = 10,
  kTrackerSilent = 11,
  kPersonLost = 12,
  kLidarSilent = 20,
  kCostmapStale = 21,
  kBaseFeedbackSilent = 30,
  kBaseFault = 31,
  kBaseEstop = 32,
  kRcOverride = 33,
  kCanBusOff = 40,
  kCanWriteErrors = 41,
  kControlOverrun = 50,
  kControlStalled = 51,
  kNumericalFailure = 52,
  kOperatorStop = 60,
  kShutdown = 61,
};

enum class Severity : uint8_t {
  kHold,      // robot holds; resumes by itself once the cause is gone for the hysteresis time
  kFault,     // latched: robot stays stopped until an operator clears it (or restart)
  kTerminal,  // shutting down: never clears
};

struct ReasonInfo {
  Reason reason;
  Severity severity;
  std::string_view name;  // stable snake_case identifier (logs, JSON)
  std::string_view text;  // for people ("HOLD: tracker silent")
};

// Listed in priority order: when several causes are present, the first one is reported as the
// primary reason (the one a person should fix first).
inline constexpr std::array<ReasonInfo, 17> kReasonTable{{
    {Reason::kShutdown, Severity::kTerminal, "shutdown", "shutting down"},
    {Reason::kBaseEstop, Severity::kFault, "base_estop", "base E-stop pressed"},
    {Reason::kBaseFault, Severity::kFault, "base_fault", "base fault bits set"},
    {Reason::kNumericalFailure, Severity::kFault, "numerical_failure",
     "policy/controller numerical failure"},
    {Reason::kControlStalled, Severity::kFault, "control_stalled", "control task stalled"},
    {Reason::kOperatorStop, Severity::kHold, "operator_stop", "operator stop"},
    {Reason::kRcOverride, Severity::kHold, "rc_override", "remote control has the base"},
    {Reason::kCanBusOff, Severity::kHold, "can_bus_off", "CAN bus-off"},
    {Reason::kCanWriteErrors, Severity::kHold, "can_write_errors", "CAN write errors"},
    {Reason::kTrackerSilent, Severity::kHold, "tracker_silent", "tracker silent"},
    {Reason::kTrackerConfidenceLow, Severity::kHold, "tracker_confidence_low",
     "tracker confidence low"},
    {Reason::kPersonLost, Severity::kHold, "person_lost", "person lost (too far)"},
    {Reason::kBaseFeedbackSilent, Severity::kHold, "base_feedback_silent", "base feedback silent"},
    {Reason::kLidarSilent, Severity::kHold, "lidar_silent", "lidar silent"},
    {Reason::kCostmapStale, Severity::kHold, "costmap_stale", "costmap stale"},
    {Reason::kControlOverrun, Severity::kHold, "control_overrun", "control task overrun"},
    {Reason::kStarting, Severity::kHold, "starting", "starting up"},
}};

inline constexpr size_t kReasonCount = kReasonTable.size();

// Dense index of a reason in kReasonTable (its priority rank); kReasonCount for kNone.
constexpr size_t reason_index(Reason r) {
  for (size_t i = 0; i < kReasonCount; ++i) {
    if (kReasonTable[i].reason == r) return i;
  }
  return kReasonCount;
}

constexpr const ReasonInfo* reason_info(Reason r) {
  const size_t i = reason_index(r);
  return i < kReasonCount ? &kReasonTable[i] : nullptr;
}

constexpr std::string_view reason_name(Reason r) {
  const ReasonInfo* info = reason_info(r);
  return info != nullptr ? info->name : std::string_view("none");
}

constexpr std::string_view reason_text(Reason r) {
  const ReasonInfo* info = reason_info(r);
  return info != nullptr ? info->text : std::string_view("none");
}

constexpr std::string_view state_name(SafetyState s) {
  switch (s) {
    case SafetyState::kInit:
      return "INIT";
    case SafetyState::kArming:
      return "ARMING";
    case SafetyState::kActive:
      return "ACTIVE";
    case SafetyState::kHold:
      return "HOLD";
    case SafetyState::kFault:
      return "FAULT";
  }
  return "?";
}

}  // namespace core
