#include <gtest/gtest.h>

#include <numbers>

#include "core/geometry/pose2.hpp"
#include "core/geometry/pose_history.hpp"

using core::Pose2;
using namespace std::chrono_literals;
using std::numbers::pi;

namespace {

TEST(Pose2, WrapAngleIsHalfOpen) {
  EXPECT_DOUBLE_EQ(core::wrap_angle(pi), pi);
  EXPECT_DOUBLE_EQ(core::wrap_angle(-pi), pi);
  EXPECT_NEAR(core::wrap_angle(3 * pi / 2), -pi / 2, 1e-12);
  EXPECT_NEAR(core::wrap_angle(-7.0), -7.0 + 2 * pi, 1e-12);
}

TEST(Pose2, ComposeAndInverse) {
  const Pose2 a{1.0, 2.0, pi / 2};
  const Pose2 b{0.5, 0.0, pi / 4};
  const Pose2 ab = a * b;
  EXPECT_NEAR(ab.x_m, 1.0, 1e-12);
  EXPECT_NEAR(ab.y_m, 2.5, 1e-12);
  EXPECT_NEAR(ab.theta_rad, 3 * pi / 4, 1e-12);
  const Pose2 id = a.inverse() * a;
  EXPECT_NEAR(id.x_m, 0, 1e-12);
  EXPECT_NEAR(id.y_m, 0, 1e-12);
  EXPECT_NEAR(id.theta_rad, 0, 1e-12);
  const auto p = a.apply({1, 0});
  EXPECT_NEAR(p.x_m, 1.0, 1e-12);
  EXPECT_NEAR(p.y_m, 3.0, 1e-12);
}

TEST(Pose2, InterpolatesTheShortWayRound) {
  const Pose2 m = core::interpolate({0, 0, 3.0}, {2, 4, -3.0}, 0.5);
  EXPECT_DOUBLE_EQ(m.x_m, 1.0);
  EXPECT_DOUBLE_EQ(m.y_m, 2.0);
  EXPECT_NEAR(std::abs(m.theta_rad), pi, 1e-9);
}

TEST(PoseHistory, InterpolatesHoldsBrieflyAndForgetsTheOldest) {
  core::PoseHistory h(4, 30ms);
  EXPECT_FALSE(h.at(0ms));
  h.add({0, 0, 0}, 0ms);
  h.add({1, 0, 0}, 20ms);
  h.add({2, 0, 0.2}, 40ms);
  EXPECT_FALSE(h.add({9, 9, 9}, 40ms)) << "stamps must increase";
  EXPECT_NEAR(h.at(30ms)->x_m, 1.5, 1e-12);
  EXPECT_NEAR(h.at(30ms)->theta_rad, 0.1, 1e-12);
  EXPECT_DOUBLE_EQ(h.at(20ms)->x_m, 1.0);
  EXPECT_DOUBLE_EQ(h.at(65ms)->x_m, 2.0) << "held up to max_extrapolation";
  EXPECT_FALSE(h.at(71ms));
  h.add({3, 0, 0}, 60ms);
  h.add({4, 0, 0}, 80ms);  // capacity 4: the pose at 0 ms is gone
  EXPECT_FALSE(h.at(10ms));
  EXPECT_NEAR(h.at(70ms)->x_m, 3.5, 1e-12);
  EXPECT_EQ(h.size(), 4U);
  EXPECT_EQ(*h.newest_stamp(), 80ms);
}

// A query newer than the newest pose (a 120 Hz tracker frame after the 50 Hz odometry) is where
// the robot has got to at its velocity since: held, a person seen from a robot driving at 1 m/s
// was placed up to 4 cm behind where they were.
TEST(PoseHistory, CarriesTheNewestPoseOnAtItsVelocity) {
  core::PoseHistory h(4, 40ms);
  h.add({0, 0, 0}, 0ms, {1.0, 0.0, 0.0});
  h.add({0.02, 0, std::numbers::pi / 2}, 20ms, {1.0, 0.5, 0.2});  // heading +y
  EXPECT_NEAR(h.at(10ms)->x_m, 0.01, 1e-12) << "between poses: interpolated, not carried";
  const auto later = h.at(50ms);  // 30 ms on: 3 cm forward (+y), 1.5 cm left (-x)
  ASSERT_TRUE(later);
  EXPECT_NEAR(later->x_m, 0.02 - 0.015, 1e-12);
  EXPECT_NEAR(later->y_m, 0.03, 1e-12);
  EXPECT_NEAR(later->theta_rad, std::numbers::pi / 2 + 0.006, 1e-12);
  EXPECT_FALSE(h.at(61ms)) << "no further than max_extrapolation";
}

}  // namespace
