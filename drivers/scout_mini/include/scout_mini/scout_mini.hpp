#pragma once
// The Scout Mini device shell: a thin layer over a hal::CanBus that keeps the base in CAN command
// mode, streams motion commands, decodes feedback into BaseState and counts everything. Time is
// passed in; bytes are parsed only by scout_codec.
#include <array>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>

#include "hal/can/can_bus.hpp"
#include "scout_mini/odometry.hpp"
#include "scout_mini/scout_codec.hpp"

namespace scout_mini {

struct ScoutConfig {
  MotionLimits limits;
  bool lateral_sign_flip = false;  // +vy is left (REP-103); flip if the firmware disagrees
  hal::Nanos feedback_timeout = std::chrono::milliseconds(200);
  hal::Nanos mode_retry_period = std::chrono::milliseconds(100);  // 0x421 re-send rate limit
  // Keep the base in CAN command mode (send 0x421 when it is not). False for listen-only tools.
  bool manage_mode = true;
};

// Per-id reception statistics.
struct IdStats {
  uint64_t count = 0;
  hal::Nanos last{0};
  double mean_interval_s = 0;  // exponentially smoothed interval between frames (0 until two)
  // Frames a second: 1 / the mean interval, not a mean of 1 / interval, which jitter biases high
  // (5 ms and 35 ms alternating read over 100 Hz for a 50 Hz stream).
  [[nodiscard]] double rate_hz() const { return mean_interval_s > 0 ? 1.0 / mean_interval_s : 0; }
};

struct MotorState {
  int16_t rpm = 0;
  double current_a = 0;
  int32_t encoder_pulses = 0;
  double driver_voltage_v = 0;
  int16_t driver_temp_c = 0;
  int8_t motor_temp_c = 0;
  uint8_t driver_state = 0;
};

struct BaseState {
  bool system_state_seen = false;
  VehicleState vehicle_state = VehicleState::kNormal;
  uint8_t control_mode_raw = 0;
  double battery_v = 0;
  uint16_t fault_word = 0;
  MotionState velocity{0, 0, 0};  // measured (0x221), vy sign-corrected
  std::optional<LightState> lights;
  std::optional<RcState> rc;
  std::array<MotorState, 4> motors{};
  std::optional<WheelOdometer> wheel_odometer;
  std::optional<VersionReply> version;
  std::optional<BmsBasic> bms;
  Pose2D odom;  // odom -> base_link
  bool protocol_v1 = false;

  [[nodiscard]] ControlMode control_mode() const {
    return static_cast<ControlMode>(control_mode_raw);
  }
  [[nodiscard]] bool in_can_mode() const {
    return system_state_seen && control_mode() == ControlMode::kCan;
  }
  [[nodiscard]] bool rc_has_control() const {
    return system_state_seen && control_mode() == ControlMode::kRemote;
  }
  [[nodiscard]] bool estop() const { return vehicle_state == VehicleState::kEstop; }
  [[nodiscard]] uint16_t stopping_faults() const { return fault_word & fault::kStopping; }
};

struct ScoutCounters {
  std::array<uint64_t, static_cast<size_t>(DecodeError::kCount)> decode_errors{};
  uint64_t commands_sent = 0;
  uint64_t commands_withheld_rc = 0;  // motion not sent: the RC holds the base
  uint64_t commands_clamped = 0;
  uint64_t commands_non_finite = 0;
  uint64_t mode_requests = 0;   // 0x421 sent
  uint64_t mode_fallbacks = 0;  // CAN mode lost after it was reached
  uint64_t write_errors = 0;    // send() failed (any reason)
  uint64_t error_frames = 0;
  uint64_t fault_clears = 0;
};

class ScoutMini {
 public:
  ScoutMini(hal::CanBus& bus, const ScoutConfig& config);

  // Drains the bus, decodes, updates state and odometry; (re-)requests CAN mode when needed.
  void poll(hal::Nanos now);
  // Sends one 0x111 with this body velocity (call at the control rate; zero is a command too).
  // Not sent while the RC holds the base. Returns the bus' answer (kOk when withheld).
  hal::CanSendResult command(double vx_mps, double vy_mps, double wz_radps, hal::Nanos now);
  // 0x441: clears latched protection faults (0 = all, 1..4 = one motor).
  hal::CanSendResult clear_faults(uint8_t which = 0);
  hal::CanSendResult request_version();
  hal::CanSendResult set_lights(bool enable, uint8_t front_mode, uint8_t front_brightness,
                                uint8_t rear_mode, uint8_t rear_brightness);

  [[nodiscard]] const BaseState& state() const { return state_; }
  [[nodiscard]] const ScoutCounters& counters() const { return counters_; }
  [[nodiscard]] const IdStats& id_stats(uint32_t can_id) const;
  // Time of the latest motion feedback (0x221) or system state (0x211); 0 if none yet.
  [[nodiscard]] hal::Nanos last_feedback() const { return last_feedback_; }
  [[nodiscard]] bool feedback_silent(hal::Nanos now) const;
  // Time of state().odom (the latest integrated 0x221); 0 if none yet.
  [[nodiscard]] hal::Nanos odom_stamp() const { return odometry_.stamp(); }
  [[nodiscard]] bool bus_off() const { return bus_.state() == hal::CanBusState::kBusOff; }
  [[nodiscard]] hal::CanBusState bus_state() const { return bus_.state(); }

 private:
  void handle(const Feedback& msg, hal::Nanos stamp);
  void count_id(uint32_t can_id, hal::Nanos stamp);
  hal::CanSendResult send(const hal::CanFrame& f);

  hal::CanBus& bus_;
  ScoutConfig config_;
  BaseState state_;
  ScoutCounters counters_;
  OdometryIntegrator odometry_;
  std::array<IdStats, 0x800> ids_{};  // indexed by 11-bit id
  hal::Nanos last_feedback_{0};
  hal::Nanos last_mode_request_{0};
  bool mode_requested_ = false;
  bool reached_can_mode_ = false;
  uint8_t light_count_ = 0;
};

}  // namespace scout_mini
