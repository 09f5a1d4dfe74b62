#pragma once
// AgileX Scout Mini (Omni) CAN protocol V2, pure: typed messages <-> CAN frames. No I/O, no
// clock. Multi-byte fields are big-endian. Facts: reference/scout_mini_can.md.
#include <array>
#include <cstdint>
#include <optional>
#include <string_view>
#include <variant>
#include <vector>

#include "hal/can/can_frame.hpp"

namespace scout_mini {

namespace id {
inline constexpr uint32_t kMotionCommand = 0x111;
inline constexpr uint32_t kLightCommand = 0x121;
inline constexpr uint32_t kControlMode = 0x421;
inline constexpr uint32_t kFaultClear = 0x441;
inline constexpr uint32_t kVersionRequest = 0x411;
inline constexpr uint32_t kSystemState = 0x211;
inline constexpr uint32_t kMotionState = 0x221;
inline constexpr uint32_t kLightState = 0x231;
inline constexpr uint32_t kRcState = 0x241;
inline constexpr uint32_t kMotorHighSpeed1 = 0x251;  // .. 0x254
inline constexpr uint32_t kMotorLowSpeed1 = 0x261;   // .. 0x264
inline constexpr uint32_t kOdometry = 0x311;
inline constexpr uint32_t kVersionReply = 0x41A;
inline constexpr uint32_t kBmsBasic = 0x361;
inline constexpr uint32_t kBmsStatus = 0x362;
inline constexpr uint32_t kV1SystemState = 0x151;  // protocol V1 (unsupported)
inline constexpr uint32_t kV1MotionCommand = 0x130;
}  // namespace id

// Every id the base sends (V2), plus the V1 status id so that V1 firmware is recognised: the
// receive filter of a SocketCAN link to the base.
const std::vector<uint32_t>& feedback_ids();

enum class ControlMode : uint8_t { kStandby = 0, kCan = 1, kSerial = 2, kRemote = 3 };
enum class VehicleState : uint8_t { kNormal = 0, kEstop = 1, kException = 2 };

// Fault word = (b4 << 8) | b5 of 0x211.
namespace fault {
inline constexpr uint16_t kBatteryUnderVoltageFault = 0x0001;  // motors cut
inline constexpr uint16_t kBatteryUnderVoltageWarning = 0x0002;
inline constexpr uint16_t kRcSignalLost = 0x0004;
inline constexpr uint16_t kMotor1CommLost = 0x0008;
inline constexpr uint16_t kMotor2CommLost = 0x0010;
inline constexpr uint16_t kMotor3CommLost = 0x0020;
inline constexpr uint16_t kMotor4CommLost = 0x0040;
inline constexpr uint16_t kMotorDriverError = 0x0100;  // [unverified]
inline constexpr uint16_t kHostCommLost = 0x0200;      // command timeout [unverified]
// Bits that mean the base cannot (or must not) drive. Warnings are reported, not acted on.
inline constexpr uint16_t kStopping = kBatteryUnderVoltageFault | kMotor1CommLost |
                                      kMotor2CommLost | kMotor3CommLost | kMotor4CommLost |
                                      kMotorDriverError;
}  // namespace fault
// Name of one fault bit ("battery_under_voltage_fault", ...), or "" for an unknown bit.
std::string_view fault_bit_name(uint16_t bit);

struct SystemState {
  VehicleState vehicle_state;
  uint8_t control_mode_raw;  // see ControlMode
  double battery_v;
  uint16_t fault_word;
  uint8_t count;
  [[nodiscard]] ControlMode control_mode() const {
    return static_cast<ControlMode>(control_mode_raw);
  }
};
struct MotionState {
  double vx_mps;
  double wz_radps;
  double vy_mps;
};
struct LightState {
  bool enabled;
  uint8_t front_mode, front_brightness, rear_mode, rear_brightness;
};
struct RcState {
  uint8_t swa, swb, swc, swd;  // 2-bit switch positions
  std::array<int8_t, 5> sticks;
};
struct MotorHighSpeed {
  uint8_t motor;  // 1..4 (1 front-right, 2 front-left, 3 rear-left, 4 rear-right)
  int16_t rpm;
  double current_a;
  int32_t encoder_pulses;
};
struct MotorLowSpeed {
  uint8_t motor;
  double driver_voltage_v;
  int16_t driver_temp_c;
  int8_t motor_temp_c;
  uint8_t driver_state;  // bit 0 supply low, 1 motor over-temp, 2 over-current, 3 driver
                         // over-temp, 4 driver link lost / sensor fault
};
struct WheelOdometer {
  int32_t left_mm;
  int32_t right_mm;
};
struct VersionReply {
  uint16_t control_hw, driver_hw, control_sw, driver_sw;  // high byte major, low byte minor
};
struct BmsBasic {
  uint8_t soc_pct;
  uint8_t soh_pct;
  double voltage_v, current_a, temperature_c;  // x0.1 [unverified scaling]
};
struct BmsStatus {
  std::array<uint8_t, 4> alarm_warning;  // raw: alarm 1, alarm 2, warning 1, warning 2
};

using Feedback = std::variant<SystemState, MotionState, LightState, RcState, MotorHighSpeed,
                              MotorLowSpeed, WheelOdometer, VersionReply, BmsBasic, BmsStatus>;

enum class DecodeError : uint8_t {
  kUnknownId,  // not a Scout feedback id (other devices may share the bus)
  kWrongDlc,   // length differs from the protocol
  kRemoteFrame,
  kExtendedId,
  kErrorFrame,
  kProtocolV1,  // a V1 id: the base runs protocol V1, which is not supported
  kCount
};
std::string_view to_string(DecodeError e);

struct Decoded {
  std::optional<Feedback> message;
  DecodeError error = DecodeError::kUnknownId;  // valid when !message
};
Decoded decode(const hal::CanFrame& frame);

struct MotionLimits {
  double vx_max_mps = 1.8;
  double vy_max_mps = 1.5;
  double wz_max_radps = 2.0;
};
struct EncodedMotion {
  hal::CanFrame frame;
  bool clamped = false;     // some component exceeded its limit
  bool non_finite = false;  // NaN/Inf replaced by 0
};
// 0x111: vx mm/s, wz 0.001 rad/s, vy mm/s (Omni), steering 0. Rounded to the nearest unit after
// clamping to the limits (and to the int16 range).
EncodedMotion encode_motion(double vx_mps, double vy_mps, double wz_radps, const MotionLimits& lim);
hal::CanFrame encode_control_mode(ControlMode mode);
hal::CanFrame encode_fault_clear(uint8_t which);  // 0 = all, 1..4 = motor
hal::CanFrame encode_version_request();
hal::CanFrame encode_lights(bool enable, uint8_t front_mode, uint8_t front_brightness,
                            uint8_t rear_mode, uint8_t rear_brightness, uint8_t count);

// Encoders of the base's side (for the simulated base and tests).
hal::CanFrame encode(const SystemState& m);
hal::CanFrame encode(const MotionState& m);
hal::CanFrame encode(const LightState& m);
hal::CanFrame encode(const MotorHighSpeed& m);
hal::CanFrame encode(const MotorLowSpeed& m);
hal::CanFrame encode(const WheelOdometer& m);
hal::CanFrame encode(const VersionReply& m);

// Decodes a 0x111 frame (the simulated base's view of a command).
std::optional<MotionState> decode_motion_command(const hal::CanFrame& frame);

}  // namespace scout_mini
