#include "sim/sim_scout_mini.hpp"

#include <algorithm>
#include <cmath>

namespace sim {

using scout_mini::ControlMode;
namespace fault = scout_mini::fault;
namespace id = scout_mini::id;

SimScoutMini::SimScoutMini(hal::CanBus& bus, const SimScoutConfig& config)
    : bus_(bus), config_(config), rng_(config.seed) {}

uint16_t SimScoutMini::fault_word() const {
  uint16_t w = 0;
  if (under_voltage_) w |= fault::kBatteryUnderVoltageFault;
  for (const bool f : motor_fault_) {
    if (f) w |= fault::kMotorDriverError;
  }
  if (timed_out_ && mode_ == ControlMode::kCan) w |= fault::kHostCommLost;
  return w;
}

bool SimScoutMini::can_drive() const {
  const bool motor_fault =
      std::any_of(motor_fault_.begin(), motor_fault_.end(), [](bool f) { return f; });
  return mode_ == ControlMode::kCan && !estop_ && !under_voltage_ && !motor_fault;
}

void SimScoutMini::set_estop(bool pressed) {
  estop_ = pressed;
  if (pressed) mode_ = ControlMode::kStandby;  // E-stop drops command mode
}
void SimScoutMini::set_rc_takeover(bool active) {
  rc_ = active;
  mode_ = active ? ControlMode::kRemote : ControlMode::kStandby;
}
void SimScoutMini::set_under_voltage(bool low) {
  under_voltage_ = low;
}
void SimScoutMini::inject_motor_fault(int motor) {
  if (motor >= 1 && motor <= 4) motor_fault_[static_cast<size_t>(motor - 1)] = true;
}
void SimScoutMini::set_feedback_silent(bool silent) {
  silent_ = silent;
}
void SimScoutMini::power_cycle() {
  mode_ = ControlMode::kStandby;
  target_ = {0, 0, 0};
  pending_.clear();
  velocity_ = {0, 0, 0};
  has_command_ = false;
  timed_out_ = false;
  motor_fault_ = {};
  count_ = 0;
}

void SimScoutMini::receive(hal::Nanos now) {
  while (auto rx = bus_.receive()) {
    const hal::CanFrame& f = rx->frame;
    if (f.error || f.extended || f.remote) continue;
    if (f.id == id::kControlMode && f.dlc >= 1) {
      // RC has priority; E-stop must be released first.
      if (f.data[0] == static_cast<uint8_t>(ControlMode::kCan) && !rc_ && !estop_) {
        mode_ = ControlMode::kCan;
      }
    } else if (f.id == id::kMotionCommand) {
      const auto cmd = scout_mini::decode_motion_command(f);
      if (cmd && mode_ == ControlMode::kCan) {
        auto clamp = [](double v, double lim) { return std::clamp(v, -lim, lim); };
        pending_.push_back({now + config_.command_latency,
                            {clamp(cmd->vx_mps, config_.limits.vx_max_mps),
                             clamp(cmd->wz_radps, config_.limits.wz_max_radps),
                             clamp(cmd->vy_mps, config_.limits.vy_max_mps)}});
        last_command_ = now;
        has_command_ = true;
        timed_out_ = false;
        ++commands_accepted_;
      } else {
        ++commands_ignored_;
      }
    } else if (f.id == id::kFaultClear && f.dlc >= 1) {
      if (f.data[0] == 0) {
        motor_fault_ = {};
      } else if (f.data[0] <= 4) {
        motor_fault_[f.data[0] - 1U] = false;
      }
    } else if (f.id == id::kVersionRequest) {
      if (!silent_) (void)bus_.send(scout_mini::encode(config_.version));
    } else if (f.id == id::kLightCommand && f.dlc == 8) {
      lights_ = {f.data[0] != 0, f.data[1], f.data[2], f.data[3], f.data[4]};
    }
  }
}

void SimScoutMini::advance(hal::Nanos now) {
  if (!started_) {
    last_step_ = now;
    next_fast_ = now;
    next_slow_ = now;
    started_ = true;
    return;
  }
  const double dt = static_cast<double>((now - last_step_).count()) * 1e-9;
  last_step_ = now;
  if (dt <= 0) return;
  while (!pending_.empty() && pending_.front().apply_at <= now) {
    target_ = pending_.front().target;
    pending_.pop_front();
  }
  if (has_command_ && now - last_command_ > config_.command_timeout) {
    target_ = {0, 0, 0};  // the real base's 500 ms command timeout
    pending_.clear();
    has_command_ = false;
    timed_out_ = true;
  }
  const scout_mini::MotionState goal = can_drive() ? target_ : scout_mini::MotionState{0, 0, 0};
  auto approach = [dt](double v, double g, double a) {
    const double step = a * dt;
    return v + std::clamp(g - v, -step, step);
  };
  velocity_.vx_mps = approach(velocity_.vx_mps, goal.vx_mps, config_.linear_accel_mps2);
  velocity_.vy_mps = approach(velocity_.vy_mps, goal.vy_mps, config_.linear_accel_mps2);
  velocity_.wz_radps = approach(velocity_.wz_radps, goal.wz_radps, config_.angular_accel_radps2);
  pose_ = scout_mini::integrate(pose_, velocity_.vx_mps, velocity_.vy_mps, velocity_.wz_radps, dt);
  left_mm_ += (velocity_.vx_mps - velocity_.wz_radps * config_.track_m / 2) * dt * 1000;
  right_mm_ += (velocity_.vx_mps + velocity_.wz_radps * config_.track_m / 2) * dt * 1000;
}

void SimScoutMini::publish(hal::Nanos now) {
  if (silent_) {
    next_fast_ = now + std::chrono::milliseconds(20);
    next_slow_ = now + std::chrono::milliseconds(100);
    return;
  }
  if (now >= next_slow_) {
    next_slow_ += std::chrono::milliseconds(100);
    if (next_slow_ <= now) next_slow_ = now + std::chrono::milliseconds(100);
    scout_mini::SystemState s{};
    s.vehicle_state = estop_ ? scout_mini::VehicleState::kEstop
                      : (fault_word() & fault::kStopping) != 0
                          ? scout_mini::VehicleState::kException
                          : scout_mini::VehicleState::kNormal;
    s.control_mode_raw = static_cast<uint8_t>(mode_);
    s.battery_v = under_voltage_ ? 21.0 : config_.battery_v;
    s.fault_word = fault_word();
    s.count = count_++;
    (void)bus_.send(scout_mini::encode(s));
    for (uint8_t m = 1; m <= 4; ++m) {
      scout_mini::MotorLowSpeed low{m, s.battery_v, 35, 30,
                                    static_cast<uint8_t>(motor_fault_[m - 1U] ? 0x04 : 0x00)};
      (void)bus_.send(scout_mini::encode(low));
    }
  }
  if (now >= next_fast_) {
    next_fast_ += std::chrono::milliseconds(20);
    if (next_fast_ <= now) next_fast_ = now + std::chrono::milliseconds(20);
    scout_mini::MotionState reported = velocity_;
    if (config_.feedback_noise_rel > 0) {
      reported.vx_mps *= 1.0 + config_.feedback_noise_rel * unit_(rng_);
      reported.vy_mps *= 1.0 + config_.feedback_noise_rel * unit_(rng_);
      reported.wz_radps *= 1.0 + config_.feedback_noise_rel * unit_(rng_);
    }
    (void)bus_.send(scout_mini::encode(reported));
    (void)bus_.send(scout_mini::encode(lights_));
    for (uint8_t m = 1; m <= 4; ++m) {
      const double wheel = velocity_.vx_mps +
                           ((m == 1 || m == 4) ? 1 : -1) * velocity_.wz_radps * config_.track_m / 2;
      const auto rpm = static_cast<int16_t>(std::lround(wheel / (M_PI * 0.1) * 60.0 * 10.0));
      scout_mini::MotorHighSpeed hs{
          m, rpm, std::abs(wheel) * 2.0,
          static_cast<int32_t>(std::lround((m % 2 ? right_mm_ : left_mm_) * 10))};
      (void)bus_.send(scout_mini::encode(hs));
    }
    (void)bus_.send(scout_mini::encode(
        scout_mini::WheelOdometer{static_cast<int32_t>(std::lround(left_mm_)),
                                  static_cast<int32_t>(std::lround(right_mm_))}));
  }
}

void SimScoutMini::step(hal::Nanos now) {
  receive(now);
  advance(now);
  publish(now);
}

}  // namespace sim
