#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/safety/motion_gate.hpp"

using namespace std::chrono_literals;
using core::BodyVelocity;
using core::MotionGate;
using core::Nanos;
using core::StopLimits;

TEST(MotionGate, PassesTheRequestOnlyWhenMotionIsAllowed) {
  MotionGate gate(StopLimits{});
  const BodyVelocity req{0.5, -0.2, 0.3};
  const auto out = gate.update(true, req, 0ms);
  EXPECT_EQ(out.vx_mps, 0.5);
  EXPECT_EQ(out.vy_mps, -0.2);
  EXPECT_EQ(out.wz_radps, 0.3);
  // Never allowed: the request never gets through, whatever it is.
  MotionGate held(StopLimits{});
  for (int i = 0; i < 100; ++i) {
    EXPECT_TRUE(held.update(false, req, i * 10ms).is_zero());
  }
}

TEST(MotionGate, StopsWithBoundedDecelerationAlongTheSameDirection) {
  StopLimits lim;
  lim.linear_decel_mps2 = 1.0;
  lim.angular_decel_radps2 = 2.0;
  lim.max_stop_time = 5s;
  MotionGate gate(lim);
  (void)gate.update(true, BodyVelocity{0.6, 0.8, -1.0}, 0ms);  // 1.0 m/s planar
  double prev_speed = 1.0;
  double prev_w = 1.0;
  Nanos t = 0ms;
  int steps = 0;
  while (true) {
    t += 10ms;
    const auto out = gate.update(false, BodyVelocity{2, 2, 2}, t);
    const double speed = std::hypot(out.vx_mps, out.vy_mps);
    EXPECT_LE(speed, prev_speed + 1e-12) << "never speeds up";
    EXPECT_GE(prev_speed - speed, 0.0);
    EXPECT_LE(prev_speed - speed, 1.0 * 0.01 + 1e-9) << "within the deceleration limit";
    EXPECT_GE(out.vx_mps, 0.0) << "never reverses";
    EXPECT_GE(out.vy_mps, 0.0);
    if (speed > 0) {
      EXPECT_NEAR(out.vx_mps / speed, 0.6, 1e-9) << "direction kept";
    }
    EXPECT_LE(out.wz_radps, 0.0);
    EXPECT_LE(std::abs(out.wz_radps), prev_w + 1e-12);
    prev_speed = speed;
    prev_w = std::abs(out.wz_radps);
    ++steps;
    if (out.is_zero()) break;
    ASSERT_LT(steps, 1000);
  }
  EXPECT_EQ(steps, 100) << "1 m/s at 1 m/s^2 takes 1 s";
  EXPECT_TRUE(gate.stopping());
}

TEST(MotionGate, StopIsExactlyZeroAfterTheMaximumStopTime) {
  StopLimits lim;
  lim.linear_decel_mps2 = 0.1;  // would take 15 s
  lim.max_stop_time = 300ms;
  MotionGate gate(lim);
  (void)gate.update(true, BodyVelocity{1.5, 0, 0}, 0ms);
  BodyVelocity out;
  // Motion stops being allowed at 10 ms: zero no later than 310 ms.
  for (Nanos t = 10ms; t < 310ms; t += 10ms) {
    out = gate.update(false, {}, t);
    EXPECT_GT(out.vx_mps, 0.0);
  }
  out = gate.update(false, {}, 310ms);
  EXPECT_TRUE(out.is_zero());
}

TEST(MotionGate, NonFiniteRequestIsRefusedAndCounted) {
  MotionGate gate(StopLimits{});
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const auto out = gate.update(true, BodyVelocity{nan, 0, 0}, 0ms);
  EXPECT_TRUE(out.is_zero());
  EXPECT_EQ(gate.rejected_non_finite(), 1U);
  const auto inf =
      gate.update(true, BodyVelocity{0, 0, std::numeric_limits<double>::infinity()}, 10ms);
  EXPECT_TRUE(inf.is_zero());
  EXPECT_EQ(gate.rejected_non_finite(), 2U);
}

TEST(MotionGate, ResumesPassingAfterAStop) {
  MotionGate gate(StopLimits{});
  (void)gate.update(true, BodyVelocity{0.4, 0, 0}, 0ms);
  (void)gate.update(false, {}, 10ms);
  const auto out = gate.update(true, BodyVelocity{0.1, 0.1, 0}, 20ms);
  EXPECT_EQ(out.vx_mps, 0.1);
  EXPECT_FALSE(gate.stopping());
}
