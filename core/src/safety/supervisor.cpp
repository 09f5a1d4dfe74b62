#include "core/safety/supervisor.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace core {
namespace {

bool stale(Nanos stamp, Nanos now, Nanos timeout) {
  return stamp == kNever || now - stamp > timeout;
}

double age_ms(Nanos stamp, Nanos now) {
  return stamp == kNever ? std::numeric_limits<double>::infinity() : to_ms(now - stamp);
}

}  // namespace

Supervisor::Supervisor(const SupervisorConfig& config) : config_(config) {
  // The ring holds at most kMaxControlOverrunsToHold; 0 would hold for ever (the loader rejects
  // both: this is the last line of defence).
  config_.control_overruns_to_hold =
      std::clamp<uint32_t>(config_.control_overruns_to_hold, 1, kMaxControlOverrunsToHold);
  for (size_t i = 0; i < kReasonCount; ++i) {
    const Reason r = kReasonTable[i].reason;
    // Faults latch in the state machine; their debounce only needs to see the cause gone.
    Nanos clear = config_.resume_after;
    if (r == Reason::kTrackerConfidenceLow) clear = config_.tracker_confidence_recover;
    if (kReasonTable[i].severity != Severity::kHold || r == Reason::kStarting) clear = Nanos(0);
    debounce_[i].set_clear_after(clear);
  }
}

ReasonSet Supervisor::evaluate(const SafetyInputs& in, Nanos now) {
  std::array<bool, kReasonCount> raw{};
  auto set = [&](Reason r, bool v) { raw[reason_index(r)] = v; };

  set(Reason::kShutdown, in.shutdown);
  set(Reason::kStarting, !in.initialized);
  set(Reason::kOperatorStop, in.operator_stop);

  if (config_.require_tracker) {
    const bool silent = stale(in.tracker_stamp, now, config_.tracker_timeout);
    set(Reason::kTrackerSilent, silent);
    // Confidence only means something for fresh data; silence is its own reason.
    set(Reason::kTrackerConfidenceLow,
        !silent && (in.tracker_confidence == TrackerConfidence::kBad ||
                    in.tracker_confidence == TrackerConfidence::kUnknown));
    set(Reason::kPersonLost, !silent && std::isfinite(in.person_distance_m) &&
                                 in.person_distance_m > config_.person_max_distance_m);
  }
  if (config_.require_lidar) {
    const bool silent = stale(in.lidar_stamp, now, config_.lidar_timeout);
    set(Reason::kLidarSilent, silent);
    set(Reason::kCostmapStale, !silent && stale(in.costmap_stamp, now, config_.costmap_max_age));
  }
  if (config_.require_base) {
    const bool silent = stale(in.base_feedback_stamp, now, config_.base_feedback_timeout);
    set(Reason::kBaseFeedbackSilent, silent);
    set(Reason::kBaseFault, in.base_fault_word != 0);
    set(Reason::kBaseEstop, in.base_estop);
    set(Reason::kRcOverride, in.rc_override);
    set(Reason::kCanBusOff, in.can_bus_off);
  }

  // Counters: a new error since the previous update trips the condition (cleared by hysteresis).
  if (counters_seen_) {
    if (config_.require_base)
      set(Reason::kCanWriteErrors, in.can_write_errors > last_write_errors_);
    const uint64_t fresh = in.control_overruns > last_overruns_
                               ? in.control_overruns - last_overruns_
                               : 0;  // a counter that went backwards: nothing new
    overruns_in_window_ = recent_overruns(fresh, now);
    set(Reason::kControlOverrun, overruns_in_window_ >= config_.control_overruns_to_hold);
  }
  counters_seen_ = true;
  last_write_errors_ = in.can_write_errors;
  last_overruns_ = in.control_overruns;

  set(Reason::kControlStalled,
      in.initialized && stale(in.control_heartbeat, now, config_.control_stall_timeout));
  set(Reason::kNumericalFailure, in.numerical_failure);

  ReasonSet active;
  for (size_t i = 0; i < kReasonCount; ++i) {
    raw_[i] = raw[i];
    active[i] = debounce_[i].update(raw[i], now);
  }
  return active;
}

uint32_t Supervisor::recent_overruns(uint64_t new_overruns, Nanos now) {
  const uint64_t record = std::min<uint64_t>(new_overruns, overrun_times_.size());
  for (uint64_t i = 0; i < record; ++i) {
    overrun_head_ = (overrun_head_ + 1) % overrun_times_.size();
    overrun_times_[overrun_head_] = now;
    overrun_count_ = std::min(overrun_count_ + 1, overrun_times_.size());
  }
  uint32_t in_window = 0;
  for (size_t i = 0; i < overrun_count_; ++i) {
    const size_t at = (overrun_head_ + overrun_times_.size() - i) % overrun_times_.size();
    if (now - overrun_times_[at] >= config_.control_overrun_window) break;  // older ones too
    ++in_window;
  }
  return in_window;
}

const char* confidence_name(TrackerConfidence c) {
  switch (c) {
    case TrackerConfidence::kGood:
      return "GOOD";
    case TrackerConfidence::kDegraded:
      return "DEGRADED";
    case TrackerConfidence::kBad:
      return "BAD";
    case TrackerConfidence::kUnknown:
      break;
  }
  return "UNKNOWN";
}

Reason Supervisor::primary(const ReasonSet& set, Severity min_severity) {
  for (size_t i = 0; i < kReasonCount; ++i) {
    if (set[i] && kReasonTable[i].severity >= min_severity) return kReasonTable[i].reason;
  }
  return Reason::kNone;
}

void Supervisor::describe(const SafetyInputs& in, Nanos now, Reason r,
                          std::array<char, 200>& out) const {
  char* buf = out.data();
  const size_t n = out.size();
  switch (r) {
    case Reason::kTrackerSilent:
      (void)std::snprintf(buf, n, "tracker age %.1f ms > timeout %.1f ms",
                          age_ms(in.tracker_stamp, now), to_ms(config_.tracker_timeout));
      break;
    case Reason::kTrackerConfidenceLow:
      (void)std::snprintf(buf, n, "tracker confidence %s (%s), quality %d, age %.1f ms",
                          confidence_name(in.tracker_confidence),
                          in.tracker_detail != nullptr ? in.tracker_detail : "", in.tracker_quality,
                          age_ms(in.tracker_stamp, now));
      break;
    case Reason::kPersonLost:
      (void)std::snprintf(buf, n, "person distance %.2f m > %.2f m", in.person_distance_m,
                          config_.person_max_distance_m);
      break;
    case Reason::kLidarSilent:
      (void)std::snprintf(buf, n, "lidar age %.1f ms > timeout %.1f ms",
                          age_ms(in.lidar_stamp, now), to_ms(config_.lidar_timeout));
      break;
    case Reason::kCostmapStale:
      (void)std::snprintf(buf, n, "costmap age %.1f ms > max %.1f ms",
                          age_ms(in.costmap_stamp, now), to_ms(config_.costmap_max_age));
      break;
    case Reason::kBaseFeedbackSilent:
      (void)std::snprintf(buf, n, "base feedback age %.1f ms > timeout %.1f ms",
                          age_ms(in.base_feedback_stamp, now),
                          to_ms(config_.base_feedback_timeout));
      break;
    case Reason::kBaseFault:
      (void)std::snprintf(buf, n, "base fault word 0x%04x", in.base_fault_word);
      break;
    case Reason::kCanWriteErrors:
      (void)std::snprintf(buf, n, "CAN write errors %llu",
                          static_cast<unsigned long long>(in.can_write_errors));
      break;
    case Reason::kControlOverrun:
      (void)std::snprintf(buf, n, "control overruns %u in the last %.0f ms (limit %u; total %llu)",
                          overruns_in_window_, to_ms(config_.control_overrun_window),
                          config_.control_overruns_to_hold,
                          static_cast<unsigned long long>(in.control_overruns));
      break;
    case Reason::kControlStalled:
      (void)std::snprintf(buf, n, "control heartbeat age %.1f ms > %.1f ms",
                          age_ms(in.control_heartbeat, now), to_ms(config_.control_stall_timeout));
      break;
    default:
      (void)std::snprintf(buf, n, "%.*s", static_cast<int>(reason_text(r).size()),
                          reason_text(r).data());
      break;
  }
}

SupervisorOutput Supervisor::update(const SafetyInputs& in, Nanos now) {
  const ReasonSet active = evaluate(in, now);
  const SafetyState prev_state = state_;
  const Reason prev_reason = reason_;

  const Reason terminal = primary(active, Severity::kTerminal);
  const Reason fault = primary(active, Severity::kFault);
  const Reason hold = primary(active, Severity::kHold);

  if (terminal != Reason::kNone) {
    state_ = SafetyState::kHold;
    reason_ = terminal;
  } else if (state_ == SafetyState::kFault) {
    // Latched: only request_fault_clear() leaves FAULT.
  } else if (fault != Reason::kNone) {
    state_ = SafetyState::kFault;
    reason_ = fault;
  } else {
    switch (state_) {
      case SafetyState::kInit:
        if (in.initialized) {
          state_ = SafetyState::kArming;
          reason_ = Reason::kNone;
          all_clear_since_ = kNever;
        }
        break;
      case SafetyState::kArming:
        if (hold != Reason::kNone) {
          state_ = SafetyState::kHold;
          reason_ = hold;
        } else {
          if (all_clear_since_ == kNever) all_clear_since_ = now;
          if (now - all_clear_since_ >= config_.arming_time) {
            state_ = SafetyState::kActive;
            reason_ = Reason::kNone;
          }
        }
        break;
      case SafetyState::kActive:
        if (hold != Reason::kNone) {
          state_ = SafetyState::kHold;
          reason_ = hold;
        }
        break;
      case SafetyState::kHold:
        // Each cause already waited `resume_after` clear in its debounce.
        if (hold == Reason::kNone) {
          state_ = SafetyState::kActive;
          reason_ = Reason::kNone;
        } else {
          reason_ = hold;
        }
        break;
      case SafetyState::kFault:
        break;
    }
  }

  SupervisorOutput out;
  out.state = state_;
  out.reason = reason_;
  out.active = active;
  out.motion_allowed = state_ == SafetyState::kActive;
  out.watchdog_ok =
      in.initialized && !stale(in.control_heartbeat, now, config_.control_stall_timeout);
  if (state_ != prev_state || reason_ != prev_reason) {
    out.transitioned = true;
    out.transition.from = prev_state;
    out.transition.to = state_;
    out.transition.reason = reason_;
    if (reason_ != Reason::kNone && !raw_[reason_index(reason_)]) {
      // A cause that already cleared and only waits out its hysteresis (HOLD -> HOLD when a
      // more important cause resolves first): say so, not the values that look healthy now.
      (void)std::snprintf(out.transition.values.data(), out.transition.values.size(),
                          "condition clear, waiting for the hysteresis");
    } else if (reason_ != Reason::kNone) {
      describe(in, now, reason_, out.transition.values);
    } else {
      (void)std::snprintf(
          out.transition.values.data(), out.transition.values.size(), "%s",
          state_ == SafetyState::kArming ? "checking inputs" : "all inputs healthy");
    }
  }
  return out;
}

bool Supervisor::request_fault_clear(const SafetyInputs& in, Nanos now) {
  if (state_ != SafetyState::kFault) return false;
  const ReasonSet active = evaluate(in, now);
  if (primary(active, Severity::kFault) != Reason::kNone) return false;
  state_ = SafetyState::kArming;
  reason_ = Reason::kNone;
  all_clear_since_ = kNever;
  return true;
}

}  // namespace core
