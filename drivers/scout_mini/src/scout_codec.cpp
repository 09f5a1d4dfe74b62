#include "scout_mini/scout_codec.hpp"

#include <algorithm>
#include <cmath>

namespace scout_mini {
namespace {

using hal::CanFrame;

int16_t s16(const CanFrame& f, int i) {
  return static_cast<int16_t>(static_cast<uint16_t>(f.data[i] << 8 | f.data[i + 1]));
}
uint16_t u16(const CanFrame& f, int i) {
  return static_cast<uint16_t>(f.data[i] << 8 | f.data[i + 1]);
}
int32_t s32(const CanFrame& f, int i) {
  return static_cast<int32_t>(static_cast<uint32_t>(f.data[i]) << 24 |
                              static_cast<uint32_t>(f.data[i + 1]) << 16 |
                              static_cast<uint32_t>(f.data[i + 2]) << 8 | f.data[i + 3]);
}
void put16(CanFrame& f, int i, int32_t v) {
  const auto u = static_cast<uint16_t>(static_cast<int16_t>(v));
  f.data[i] = static_cast<uint8_t>(u >> 8);
  f.data[i + 1] = static_cast<uint8_t>(u & 0xFF);
}
void put32(CanFrame& f, int i, int32_t v) {
  const auto u = static_cast<uint32_t>(v);
  for (int k = 0; k < 4; ++k)
    f.data[i + k] = static_cast<uint8_t>(u >> (24 - 8 * k));
}
CanFrame frame(uint32_t id, uint8_t dlc) {
  CanFrame f;
  f.id = id;
  f.dlc = dlc;
  return f;
}
// Rounds `value / unit` to an int16 after clamping |value| <= limit.
int32_t quantise(double value, double limit, double unit, bool& clamped, bool& non_finite) {
  if (!std::isfinite(value)) {
    non_finite = true;
    return 0;
  }
  if (std::abs(value) > limit) {
    clamped = true;
    value = std::copysign(limit, value);
  }
  const double q = std::round(value / unit);
  return static_cast<int32_t>(std::clamp(q, -32768.0, 32767.0));
}

}  // namespace

const std::vector<uint32_t>& feedback_ids() {
  static const std::vector<uint32_t> kIds{id::kSystemState,
                                          id::kMotionState,
                                          id::kLightState,
                                          id::kRcState,
                                          0x251,
                                          0x252,
                                          0x253,
                                          0x254,
                                          0x261,
                                          0x262,
                                          0x263,
                                          0x264,
                                          id::kOdometry,
                                          id::kVersionReply,
                                          id::kBmsBasic,
                                          id::kBmsStatus,
                                          id::kV1SystemState};
  return kIds;
}

std::string_view fault_bit_name(uint16_t bit) {
  switch (bit) {
    case fault::kBatteryUnderVoltageFault:
      return "battery_under_voltage_fault";
    case fault::kBatteryUnderVoltageWarning:
      return "battery_under_voltage_warning";
    case fault::kRcSignalLost:
      return "rc_signal_lost";
    case fault::kMotor1CommLost:
      return "motor1_comm_lost";
    case fault::kMotor2CommLost:
      return "motor2_comm_lost";
    case fault::kMotor3CommLost:
      return "motor3_comm_lost";
    case fault::kMotor4CommLost:
      return "motor4_comm_lost";
    case fault::kMotorDriverError:
      return "motor_driver_error";
    case fault::kHostCommLost:
      return "host_comm_lost";
    default:
      return "";
  }
}

std::string_view to_string(DecodeError e) {
  switch (e) {
    case DecodeError::kUnknownId:
      return "unknown_id";
    case DecodeError::kWrongDlc:
      return "wrong_dlc";
    case DecodeError::kRemoteFrame:
      return "remote_frame";
    case DecodeError::kExtendedId:
      return "extended_id";
    case DecodeError::kErrorFrame:
      return "error_frame";
    case DecodeError::kProtocolV1:
      return "protocol_v1";
    case DecodeError::kCount:
      break;
  }
  return "?";
}

// GCC 12 reports -Wmaybe-uninitialized inside std::variant's storage when an optional<variant>
// is assigned here (a known false positive of GCC's variant/optional analysis); every member of
// every message is initialised below.
#pragma GCC diagnostic push
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
Decoded decode(const CanFrame& f) {
  Decoded d;
  auto fail = [&](DecodeError e) {
    d.error = e;
    return d;
  };
  if (f.error) return fail(DecodeError::kErrorFrame);
  if (f.extended) return fail(DecodeError::kExtendedId);
  if (f.id == id::kV1SystemState || f.id == id::kV1MotionCommand)
    return fail(DecodeError::kProtocolV1);
  const bool known =
      f.id == id::kSystemState || f.id == id::kMotionState || f.id == id::kLightState ||
      f.id == id::kRcState || (f.id >= id::kMotorHighSpeed1 && f.id <= id::kMotorHighSpeed1 + 3) ||
      (f.id >= id::kMotorLowSpeed1 && f.id <= id::kMotorLowSpeed1 + 3) || f.id == id::kOdometry ||
      f.id == id::kVersionReply || f.id == id::kBmsBasic || f.id == id::kBmsStatus;
  if (!known) return fail(DecodeError::kUnknownId);
  if (f.remote) return fail(DecodeError::kRemoteFrame);
  if (f.dlc != 8) return fail(DecodeError::kWrongDlc);

  if (f.id == id::kSystemState) {
    d.message = SystemState{static_cast<VehicleState>(f.data[0]), f.data[1], u16(f, 2) * 0.1,
                            static_cast<uint16_t>(f.data[4] << 8 | f.data[5]), f.data[7]};
  } else if (f.id == id::kMotionState) {
    d.message = MotionState{s16(f, 0) * 0.001, s16(f, 2) * 0.001, s16(f, 4) * 0.001};
  } else if (f.id == id::kLightState) {
    d.message = LightState{f.data[0] != 0, f.data[1], f.data[2], f.data[3], f.data[4]};
  } else if (f.id == id::kRcState) {
    RcState rc{};
    rc.swa = f.data[0] & 0x3;
    rc.swb = (f.data[0] >> 2) & 0x3;
    rc.swc = (f.data[0] >> 4) & 0x3;
    rc.swd = (f.data[0] >> 6) & 0x3;
    for (int i = 0; i < 5; ++i)
      rc.sticks[static_cast<size_t>(i)] = static_cast<int8_t>(f.data[1 + i]);
    d.message = rc;
  } else if (f.id >= id::kMotorHighSpeed1 && f.id <= id::kMotorHighSpeed1 + 3) {
    d.message = MotorHighSpeed{static_cast<uint8_t>(f.id - id::kMotorHighSpeed1 + 1), s16(f, 0),
                               s16(f, 2) * 0.1, s32(f, 4)};
  } else if (f.id >= id::kMotorLowSpeed1 && f.id <= id::kMotorLowSpeed1 + 3) {
    d.message = MotorLowSpeed{static_cast<uint8_t>(f.id - id::kMotorLowSpeed1 + 1), u16(f, 0) * 0.1,
                              s16(f, 2), static_cast<int8_t>(f.data[4]), f.data[5]};
  } else if (f.id == id::kOdometry) {
    d.message = WheelOdometer{s32(f, 0), s32(f, 4)};
  } else if (f.id == id::kVersionReply) {
    d.message = VersionReply{u16(f, 0), u16(f, 2), u16(f, 4), u16(f, 6)};
  } else if (f.id == id::kBmsBasic) {
    d.message = BmsBasic{f.data[0], f.data[1], u16(f, 2) * 0.1, s16(f, 4) * 0.1, s16(f, 6) * 0.1};
  } else {
    d.message = BmsStatus{{f.data[0], f.data[1], f.data[2], f.data[3]}};
  }
  return d;
}
#pragma GCC diagnostic pop

EncodedMotion encode_motion(double vx, double vy, double wz, const MotionLimits& lim) {
  EncodedMotion out;
  out.frame = frame(id::kMotionCommand, 8);
  put16(out.frame, 0, quantise(vx, lim.vx_max_mps, 0.001, out.clamped, out.non_finite));
  put16(out.frame, 2, quantise(wz, lim.wz_max_radps, 0.001, out.clamped, out.non_finite));
  put16(out.frame, 4, quantise(vy, lim.vy_max_mps, 0.001, out.clamped, out.non_finite));
  if (out.non_finite) {
    // Never send part of a broken command: all or nothing.
    out.frame.data.fill(0);
  }
  return out;
}

CanFrame encode_control_mode(ControlMode mode) {
  CanFrame f = frame(id::kControlMode, 1);
  f.data[0] = static_cast<uint8_t>(mode);
  return f;
}
CanFrame encode_fault_clear(uint8_t which) {
  CanFrame f = frame(id::kFaultClear, 1);
  f.data[0] = which;
  return f;
}
CanFrame encode_version_request() {
  CanFrame f = frame(id::kVersionRequest, 1);
  f.data[0] = 0x01;
  return f;
}
CanFrame encode_lights(bool enable, uint8_t fm, uint8_t fb, uint8_t rm, uint8_t rb, uint8_t count) {
  CanFrame f = frame(id::kLightCommand, 8);
  f.data = {static_cast<uint8_t>(enable ? 1 : 0),
            fm,
            std::min<uint8_t>(fb, 100),
            rm,
            std::min<uint8_t>(rb, 100),
            0,
            0,
            count};
  return f;
}

CanFrame encode(const SystemState& m) {
  CanFrame f = frame(id::kSystemState, 8);
  f.data[0] = static_cast<uint8_t>(m.vehicle_state);
  f.data[1] = m.control_mode_raw;
  put16(f, 2, static_cast<int32_t>(std::lround(m.battery_v * 10)));
  f.data[4] = static_cast<uint8_t>(m.fault_word >> 8);
  f.data[5] = static_cast<uint8_t>(m.fault_word & 0xFF);
  f.data[7] = m.count;
  return f;
}
CanFrame encode(const MotionState& m) {
  CanFrame f = frame(id::kMotionState, 8);
  put16(f, 0, static_cast<int32_t>(std::lround(m.vx_mps * 1000)));
  put16(f, 2, static_cast<int32_t>(std::lround(m.wz_radps * 1000)));
  put16(f, 4, static_cast<int32_t>(std::lround(m.vy_mps * 1000)));
  return f;
}
CanFrame encode(const LightState& m) {
  CanFrame f = frame(id::kLightState, 8);
  f.data = {static_cast<uint8_t>(m.enabled ? 1 : 0),
            m.front_mode,
            m.front_brightness,
            m.rear_mode,
            m.rear_brightness,
            0,
            0,
            0};
  return f;
}
CanFrame encode(const MotorHighSpeed& m) {
  CanFrame f = frame(id::kMotorHighSpeed1 + m.motor - 1, 8);
  put16(f, 0, m.rpm);
  put16(f, 2, static_cast<int32_t>(std::lround(m.current_a * 10)));
  put32(f, 4, m.encoder_pulses);
  return f;
}
CanFrame encode(const MotorLowSpeed& m) {
  CanFrame f = frame(id::kMotorLowSpeed1 + m.motor - 1, 8);
  put16(f, 0, static_cast<int32_t>(std::lround(m.driver_voltage_v * 10)));
  put16(f, 2, m.driver_temp_c);
  f.data[4] = static_cast<uint8_t>(m.motor_temp_c);
  f.data[5] = m.driver_state;
  return f;
}
CanFrame encode(const WheelOdometer& m) {
  CanFrame f = frame(id::kOdometry, 8);
  put32(f, 0, m.left_mm);
  put32(f, 4, m.right_mm);
  return f;
}
CanFrame encode(const VersionReply& m) {
  CanFrame f = frame(id::kVersionReply, 8);
  put16(f, 0, m.control_hw);
  put16(f, 2, m.driver_hw);
  put16(f, 4, m.control_sw);
  put16(f, 6, m.driver_sw);
  return f;
}

std::optional<MotionState> decode_motion_command(const CanFrame& f) {
  if (f.id != id::kMotionCommand || f.extended || f.remote || f.error || f.dlc != 8)
    return std::nullopt;
  return MotionState{s16(f, 0) * 0.001, s16(f, 2) * 0.001, s16(f, 4) * 0.001};
}

}  // namespace scout_mini
