#include "scout_mini/scout_mini.hpp"

#include <type_traits>

namespace scout_mini {

ScoutMini::ScoutMini(hal::CanBus& bus, const ScoutConfig& config) : bus_(bus), config_(config) {
  odometry_.max_gap = config_.feedback_timeout;
}

const IdStats& ScoutMini::id_stats(uint32_t can_id) const {
  return ids_[can_id & 0x7FF];
}

bool ScoutMini::feedback_silent(hal::Nanos now) const {
  return last_feedback_ == hal::Nanos(0) || now - last_feedback_ > config_.feedback_timeout;
}

hal::CanSendResult ScoutMini::send(const hal::CanFrame& f) {
  const hal::CanSendResult r = bus_.send(f);
  if (r != hal::CanSendResult::kOk) ++counters_.write_errors;
  return r;
}

void ScoutMini::count_id(uint32_t can_id, hal::Nanos stamp) {
  IdStats& s = ids_[can_id & 0x7FF];
  if (s.count > 0 && stamp > s.last) {
    // Smooth the interval, not its reciprocal (IdStats::rate_hz says why).
    const double interval_s = 1e-9 * static_cast<double>((stamp - s.last).count());
    s.mean_interval_s = s.count == 1 ? interval_s : 0.8 * s.mean_interval_s + 0.2 * interval_s;
  }
  ++s.count;
  s.last = stamp;
}

void ScoutMini::handle(const Feedback& msg, hal::Nanos stamp) {
  std::visit(
      [&](const auto& m) {
        using T = std::decay_t<decltype(m)>;
        if constexpr (std::is_same_v<T, SystemState>) {
          const bool was_can = state_.in_can_mode();
          state_.system_state_seen = true;
          state_.vehicle_state = m.vehicle_state;
          state_.control_mode_raw = m.control_mode_raw;
          state_.battery_v = m.battery_v;
          state_.fault_word = m.fault_word;
          if (state_.in_can_mode()) reached_can_mode_ = true;
          if (was_can && !state_.in_can_mode()) ++counters_.mode_fallbacks;
          last_feedback_ = stamp;
        } else if constexpr (std::is_same_v<T, MotionState>) {
          MotionState v = m;
          if (config_.lateral_sign_flip) v.vy_mps = -v.vy_mps;
          state_.velocity = v;
          odometry_.add(v.vx_mps, v.vy_mps, v.wz_radps, stamp);
          state_.odom = odometry_.pose();
          last_feedback_ = stamp;
        } else if constexpr (std::is_same_v<T, LightState>) {
          state_.lights = m;
        } else if constexpr (std::is_same_v<T, RcState>) {
          state_.rc = m;
        } else if constexpr (std::is_same_v<T, MotorHighSpeed>) {
          auto& mo = state_.motors[m.motor - 1];
          mo.rpm = m.rpm;
          mo.current_a = m.current_a;
          mo.encoder_pulses = m.encoder_pulses;
        } else if constexpr (std::is_same_v<T, MotorLowSpeed>) {
          auto& mo = state_.motors[m.motor - 1];
          mo.driver_voltage_v = m.driver_voltage_v;
          mo.driver_temp_c = m.driver_temp_c;
          mo.motor_temp_c = m.motor_temp_c;
          mo.driver_state = m.driver_state;
        } else if constexpr (std::is_same_v<T, WheelOdometer>) {
          state_.wheel_odometer = m;
        } else if constexpr (std::is_same_v<T, VersionReply>) {
          state_.version = m;
        } else if constexpr (std::is_same_v<T, BmsBasic>) {
          state_.bms = m;
        } else if constexpr (std::is_same_v<T, BmsStatus>) {
          // Raw alarm bytes are not acted upon (unverified on the Mini).
        }
      },
      msg);
}

void ScoutMini::poll(hal::Nanos now) {
  while (auto rx = bus_.receive()) {
    if (rx->frame.error) {
      ++counters_.error_frames;
      continue;
    }
    const Decoded d = decode(rx->frame);
    if (!d.message) {
      ++counters_.decode_errors[static_cast<size_t>(d.error)];
      if (d.error == DecodeError::kProtocolV1) state_.protocol_v1 = true;
      continue;
    }
    count_id(rx->frame.id, rx->stamp);
    handle(*d.message, rx->stamp);
  }
  // Keep CAN command mode: after power-on, E-stop or an RC takeover the base falls back to
  // standby and ignores 0x111 until it sees 0x421 again. Never while a person holds the RC.
  if (config_.manage_mode && !state_.in_can_mode() && !state_.rc_has_control() &&
      !state_.protocol_v1 &&
      (!mode_requested_ || now - last_mode_request_ >= config_.mode_retry_period)) {
    if (send(encode_control_mode(ControlMode::kCan)) == hal::CanSendResult::kOk) {
      ++counters_.mode_requests;
    }
    last_mode_request_ = now;
    mode_requested_ = true;
  }
}

hal::CanSendResult ScoutMini::command(double vx, double vy, double wz, hal::Nanos /*now*/) {
  if (state_.rc_has_control()) {
    ++counters_.commands_withheld_rc;
    return hal::CanSendResult::kOk;
  }
  const double vy_wire = config_.lateral_sign_flip ? -vy : vy;
  const EncodedMotion m = encode_motion(vx, vy_wire, wz, config_.limits);
  if (m.clamped) ++counters_.commands_clamped;
  if (m.non_finite) ++counters_.commands_non_finite;
  const hal::CanSendResult r = send(m.frame);
  if (r == hal::CanSendResult::kOk) ++counters_.commands_sent;
  return r;
}

hal::CanSendResult ScoutMini::clear_faults(uint8_t which) {
  ++counters_.fault_clears;
  return send(encode_fault_clear(which));
}

hal::CanSendResult ScoutMini::request_version() {
  return send(encode_version_request());
}

hal::CanSendResult ScoutMini::set_lights(bool enable, uint8_t fm, uint8_t fb, uint8_t rm,
                                         uint8_t rb) {
  return send(encode_lights(enable, fm, fb, rm, rb, light_count_++));
}

}  // namespace scout_mini
