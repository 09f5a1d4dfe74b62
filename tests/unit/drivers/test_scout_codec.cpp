#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "hal/can/candump_log.hpp"
#include "scout_mini/odometry.hpp"
#include "scout_mini/scout_codec.hpp"

using hal::CanFrame;
namespace sm = scout_mini;

namespace {
// A frame from the reference's cansend notation, via our candump parser.
CanFrame frame(const std::string& cansend) {
  hal::CandumpRecord r;
  std::string err;
  EXPECT_EQ(hal::parse_candump_line("(0.000000) can0 " + cansend, r, err),
            hal::CandumpParse::kRecord)
      << err;
  return r.frame;
}
const sm::MotionLimits kWide{3.0, 2.0, 2.5235};
}  // namespace

TEST(ScoutCodec, EncodesTheReferenceWorkedFrames) {
  EXPECT_EQ(sm::encode_control_mode(sm::ControlMode::kCan), frame("421#01"));
  EXPECT_EQ(sm::encode_motion(0.15, 0, 0, kWide).frame, frame("111#0096000000000000"));
  EXPECT_EQ(sm::encode_motion(0, 0, 0.05, kWide).frame, frame("111#0000003200000000"));
  EXPECT_EQ(sm::encode_motion(-0.15, 0, 0, kWide).frame, frame("111#FF6A000000000000"));
  EXPECT_EQ(sm::encode_motion(0, 0.2, 0, kWide).frame, frame("111#0000000000C80000"));
  EXPECT_EQ(sm::encode_fault_clear(0), frame("441#00"));
  EXPECT_EQ(sm::encode_version_request(), frame("411#01"));
}

TEST(ScoutCodec, MotionCommandRoundsAndClamps) {
  auto m = sm::encode_motion(0.1234, -0.0006, 0.0004, kWide);
  auto back = sm::decode_motion_command(m.frame);
  ASSERT_TRUE(back);
  EXPECT_DOUBLE_EQ(back->vx_mps, 0.123);
  EXPECT_DOUBLE_EQ(back->vy_mps, -0.001) << "rounded to the nearest mm/s";
  EXPECT_DOUBLE_EQ(back->wz_radps, 0.0);
  EXPECT_FALSE(m.clamped);

  const sm::MotionLimits lim{1.8, 1.5, 2.0};
  m = sm::encode_motion(5.0, -4.0, -9.0, lim);
  back = sm::decode_motion_command(m.frame);
  EXPECT_TRUE(m.clamped);
  EXPECT_DOUBLE_EQ(back->vx_mps, 1.8);
  EXPECT_DOUBLE_EQ(back->vy_mps, -1.5);
  EXPECT_DOUBLE_EQ(back->wz_radps, -2.0);

  m = sm::encode_motion(0.5, NAN, 0.1, lim);
  EXPECT_TRUE(m.non_finite);
  EXPECT_EQ(m.frame, frame("111#0000000000000000")) << "a broken command is sent as zero, whole";
}

TEST(ScoutCodec, LightsCommandLayout) {
  EXPECT_EQ(sm::encode_lights(true, 1, 150, 2, 50, 7), frame("121#0101640232000007"))
      << "brightness clamped to 100, rolling count in b7";
}

TEST(ScoutCodec, DecodesSystemState) {
  const auto d = sm::decode(frame("211#0001010E00480005"));
  ASSERT_TRUE(d.message);
  const auto& s = std::get<sm::SystemState>(*d.message);
  EXPECT_EQ(s.vehicle_state, sm::VehicleState::kNormal);
  EXPECT_EQ(s.control_mode(), sm::ControlMode::kCan);
  EXPECT_DOUBLE_EQ(s.battery_v, 27.0);
  EXPECT_EQ(s.fault_word, 0x0048) << "(b4 << 8) | b5: motor 1 and motor 4 comm lost";
  EXPECT_EQ(s.count, 5);
  EXPECT_EQ(sm::fault_bit_name(0x0040), "motor4_comm_lost");
  EXPECT_EQ(sm::fault_bit_name(0x8000), "") << "unknown bits stay visible as raw values";
}

TEST(ScoutCodec, DecodesMotionStateLikeTheCommand) {
  const auto ok = sm::decode(frame("221#FF6A003200C80000"));
  ASSERT_TRUE(ok.message);
  const auto& m = std::get<sm::MotionState>(*ok.message);
  EXPECT_DOUBLE_EQ(m.vx_mps, -0.15);
  EXPECT_DOUBLE_EQ(m.wz_radps, 0.05);
  EXPECT_DOUBLE_EQ(m.vy_mps, 0.2);
}

TEST(ScoutCodec, DecodesEveryFeedbackId) {
  auto msg = [](const std::string& f) {
    const auto d = sm::decode(frame(f));
    EXPECT_TRUE(d.message) << f << " " << sm::to_string(d.error);
    return *d.message;
  };
  const auto light = std::get<sm::LightState>(msg("231#0101640232000000"));
  EXPECT_TRUE(light.enabled);
  EXPECT_EQ(light.front_brightness, 100);
  const auto rc = std::get<sm::RcState>(msg("241#E47F81000A000000"));
  EXPECT_EQ(rc.swa, 0);
  EXPECT_EQ(rc.swb, 1);
  EXPECT_EQ(rc.swc, 2);
  EXPECT_EQ(rc.swd, 3);
  EXPECT_EQ(rc.sticks[0], 127);
  EXPECT_EQ(rc.sticks[1], -127);
  for (int m = 1; m <= 4; ++m) {
    const auto hs =
        std::get<sm::MotorHighSpeed>(msg(std::to_string(250 + m) + "#FC18000F00012345"));
    EXPECT_EQ(hs.motor, m);
    EXPECT_EQ(hs.rpm, -1000);
    EXPECT_DOUBLE_EQ(hs.current_a, 1.5);
    EXPECT_EQ(hs.encoder_pulses, 0x12345);
    const auto ls = std::get<sm::MotorLowSpeed>(msg(std::to_string(260 + m) + "#00FC002AE6050000"));
    EXPECT_EQ(ls.motor, m);
    EXPECT_DOUBLE_EQ(ls.driver_voltage_v, 25.2);
    EXPECT_EQ(ls.driver_temp_c, 42);
    EXPECT_EQ(ls.motor_temp_c, -26);
    EXPECT_EQ(ls.driver_state, 0x05);
  }
  const auto odo = std::get<sm::WheelOdometer>(msg("311#FFFFFC1800000BB8"));
  EXPECT_EQ(odo.left_mm, -1000);
  EXPECT_EQ(odo.right_mm, 3000);
  const auto ver = std::get<sm::VersionReply>(msg("41A#0102010302050104"));
  EXPECT_EQ(ver.control_sw, 0x0205);
  const auto bms = std::get<sm::BmsBasic>(msg("361#5F6400FCFFF6012C"));
  EXPECT_EQ(bms.soc_pct, 95);
  EXPECT_DOUBLE_EQ(bms.voltage_v, 25.2);
  EXPECT_DOUBLE_EQ(bms.current_a, -1.0);
  EXPECT_DOUBLE_EQ(bms.temperature_c, 30.0);
  const auto st = std::get<sm::BmsStatus>(msg("362#0102030400000000"));
  EXPECT_EQ(st.alarm_warning[3], 4);
}

TEST(ScoutCodec, EncodersOfTheBaseRoundTrip) {
  const sm::SystemState s{sm::VehicleState::kEstop, 3, 24.6, 0x0204, 9};
  const auto back = std::get<sm::SystemState>(*sm::decode(sm::encode(s)).message);
  EXPECT_EQ(back.vehicle_state, s.vehicle_state);
  EXPECT_EQ(back.control_mode_raw, 3);
  EXPECT_DOUBLE_EQ(back.battery_v, 24.6);
  EXPECT_EQ(back.fault_word, 0x0204);
  const sm::MotorHighSpeed hs{3, -250, 2.5, -77};
  const auto hs2 = std::get<sm::MotorHighSpeed>(*sm::decode(sm::encode(hs)).message);
  EXPECT_EQ(hs2.motor, 3);
  EXPECT_EQ(hs2.encoder_pulses, -77);
}

TEST(ScoutCodec, RejectsMalformedFramesWithAReason) {
  EXPECT_EQ(sm::decode(frame("211#0001")).error, sm::DecodeError::kWrongDlc);
  EXPECT_EQ(sm::decode(frame("221#R")).error, sm::DecodeError::kRemoteFrame);
  EXPECT_EQ(sm::decode(frame("00000221#0000000000000000")).error, sm::DecodeError::kExtendedId);
  EXPECT_EQ(sm::decode(frame("20000040#0000000000000000")).error, sm::DecodeError::kErrorFrame);
  EXPECT_EQ(sm::decode(frame("151#0000000000000000")).error, sm::DecodeError::kProtocolV1);
  EXPECT_EQ(sm::decode(frame("123#00")).error, sm::DecodeError::kUnknownId);
  EXPECT_FALSE(sm::decode_motion_command(frame("111#0096")));
}

// Fuzz-style: random ids (around the Scout's), lengths, flags and bytes. No crash, every frame
// either decodes or is dropped with a reason, and decoded values stay in their wire ranges.
TEST(ScoutCodec, RandomFramesNeverCrashAndAreCountedWhenDropped) {
  std::minstd_rand rng(2026);
  std::array<uint64_t, static_cast<size_t>(sm::DecodeError::kCount)> drops{};
  uint64_t decoded = 0;
  for (int i = 0; i < 200000; ++i) {
    CanFrame f;
    const auto r = static_cast<uint32_t>(rng());
    f.id = (r & 1) ? 0x100 + static_cast<uint32_t>(rng() % 0x400)
                   : static_cast<uint32_t>(rng() & 0x7FF);
    f.extended = (r & 0x30) == 0x30;
    f.remote = (r & 0x1C0) == 0x1C0;
    f.error = (r & 0xE00) == 0xE00;
    f.dlc = static_cast<uint8_t>((r >> 12) % 9);
    if ((r >> 20) % 4 != 0) f.dlc = 8;
    for (auto& b : f.data)
      b = static_cast<uint8_t>(rng());
    const auto d = sm::decode(f);
    if (d.message) {
      ++decoded;
      if (const auto* m = std::get_if<sm::MotionState>(&*d.message)) {
        ASSERT_LE(std::abs(m->vx_mps), 32.768);
      }
      if (const auto* hs = std::get_if<sm::MotorHighSpeed>(&*d.message)) {
        ASSERT_GE(hs->motor, 1);
        ASSERT_LE(hs->motor, 4);
      }
    } else {
      ++drops[static_cast<size_t>(d.error)];
    }
  }
  EXPECT_GT(decoded, 1000U);
  EXPECT_GT(drops[static_cast<size_t>(sm::DecodeError::kWrongDlc)], 0U);
  EXPECT_GT(drops[static_cast<size_t>(sm::DecodeError::kUnknownId)], 0U);
  uint64_t total = decoded;
  for (const auto d : drops)
    total += d;
  EXPECT_EQ(total, 200000U);
}

TEST(Odometry, StraightLineLateralAndArc) {
  sm::Pose2D p;
  p = sm::integrate(p, 1.0, 0.0, 0.0, 2.0);
  EXPECT_NEAR(p.x_m, 2.0, 1e-12);
  p = sm::integrate(sm::Pose2D{0, 0, M_PI / 2}, 0.0, 0.5, 0.0, 2.0);
  EXPECT_NEAR(p.x_m, -1.0, 1e-12) << "lateral (+y, left) motion facing +y goes to -x";
  EXPECT_NEAR(p.y_m, 0.0, 1e-12);
  // Quarter circle of radius 1: v = 1, w = 1 for pi/2 s, in 100 steps, stays on the circle.
  sm::OdometryIntegrator odo;
  const auto dt = std::chrono::nanoseconds(static_cast<int64_t>(M_PI / 2 / 100 * 1e9));
  for (int i = 0; i <= 100; ++i)
    odo.add(1.0, 0.0, 1.0, dt * i);
  EXPECT_NEAR(odo.pose().x_m, 1.0, 1e-6);
  EXPECT_NEAR(odo.pose().y_m, 1.0, 1e-6);
  EXPECT_NEAR(odo.pose().theta_rad, M_PI / 2, 1e-6);
}

TEST(Odometry, GapsAreNotIntegrated) {
  sm::OdometryIntegrator odo;
  odo.add(1.0, 0, 0, std::chrono::milliseconds(0));
  odo.add(1.0, 0, 0, std::chrono::milliseconds(20));
  odo.add(1.0, 0, 0, std::chrono::milliseconds(2000));  // 1.98 s of silence
  EXPECT_NEAR(odo.pose().x_m, 0.02, 1e-12);
}

TEST(ScoutCodec, FeedbackIdsCoverEveryDecodedIdAndV1) {
  const auto& ids = sm::feedback_ids();
  for (uint32_t id = 0; id < 0x800; ++id) {
    CanFrame f;
    f.id = id;
    f.dlc = 8;
    const auto d = sm::decode(f);
    const bool wanted = d.message.has_value() || d.error == sm::DecodeError::kProtocolV1;
    const bool listed = std::find(ids.begin(), ids.end(), id) != ids.end();
    if (id == sm::id::kV1MotionCommand) continue;  // host -> base in V1: never received
    EXPECT_EQ(wanted, listed) << std::hex << id;
  }
}
