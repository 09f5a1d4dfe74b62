// Speed and separation toward the person (core/control/closing_speed.hpp).
#include <gtest/gtest.h>

#include <cmath>

#include "core/control/closing_speed.hpp"

using core::ClosingSpeedConfig;
using core::Point2;
using core::Twist;

namespace {

ClosingSpeedConfig on(double decel = 1.0) {
  ClosingSpeedConfig c;
  c.robot_decel_mps2 = decel;
  return c;
}

const core::TwistLimits kLimits{1.8, 1.5, 2.0};

// The person's centre `gap` ahead of the footprint's front face (plus their radius).
Point2 ahead(double gap_m, const ClosingSpeedConfig& c) {
  return {c.footprint.x_max_m + c.person_radius_m + gap_m, 0.0};
}

}  // namespace

TEST(ClosingSpeed, OffLeavesTheCommandAlone) {
  const ClosingSpeedConfig c;  // robot_decel_mps2 = 0
  const auto r =
      core::limit_closing_speed(ahead(0.05, c), {0, 0}, Twist{1.5, 0.2, 0.3}, c, kLimits);
  EXPECT_FALSE(r.limited);
  EXPECT_DOUBLE_EQ(r.u.vx, 1.5);
  EXPECT_DOUBLE_EQ(r.u.vy, 0.2);
  EXPECT_DOUBLE_EQ(r.u.wz, 0.3);
}

// The robot's way to a stop from v plus the person's way toward it meanwhile.
double closed_in_a_stop(double v, double receding, double speed, const ClosingSpeedConfig& c) {
  const double stop_s = c.reaction_time_s + v / c.robot_decel_mps2;
  return v * c.reaction_time_s + v * v / (2.0 * c.robot_decel_mps2) +
         core::person_approach_m(stop_s, receding, speed, c.person_accel_mps2);
}

TEST(ClosingSpeed, TheLimitStopsInTheGapLeft) {
  const ClosingSpeedConfig c = on(1.0);
  for (const double gap : {0.15, 0.3, 0.6, 1.2}) {
    const double v = core::max_closing_speed(gap, 0.0, 0.0, c);  // a person standing still
    // reaction, then braking: exactly the room between the bodies less the margin
    EXPECT_NEAR(v * c.reaction_time_s + v * v / (2.0 * c.robot_decel_mps2), gap - c.margin_m, 1e-9)
        << gap;
  }
  EXPECT_DOUBLE_EQ(core::max_closing_speed(c.margin_m, 0.0, 0.0, c), 0.0);
  EXPECT_DOUBLE_EQ(core::max_closing_speed(-0.2, 0.0, 0.0, c), 0.0) << "overlapping: never closer";
}

TEST(ClosingSpeed, APersonWalkingAwayMayStopAndOneWalkingAcrossMayTurnIntoTheRobot) {
  // straight away at 1.4 m/s, stopping at 3 m/s^2: 0.33 m farther, then standing
  EXPECT_NEAR(core::person_approach_m(0.2, 1.4, 1.4, 3.0), -1.4 * 0.2 + 1.5 * 0.04, 1e-12);
  EXPECT_NEAR(core::person_approach_m(2.0, 1.4, 1.4, 3.0), -1.4 * 1.4 / 6.0, 1e-12);
  // across at 1.2 m/s: turning into the robot, at most at their speed
  EXPECT_NEAR(core::person_approach_m(0.2, 0.0, 1.2, 3.0), 1.5 * 0.04, 1e-12);
  EXPECT_NEAR(core::person_approach_m(2.0, 0.0, 1.2, 3.0), 0.24 + 1.2 * 1.6, 1e-12);
  // toward it: from their speed on
  EXPECT_NEAR(core::person_approach_m(0.5, -1.0, 1.0, 3.0), 0.5, 1e-12);
  // no turning allowed: their velocity as it is
  EXPECT_NEAR(core::person_approach_m(1.0, 0.7, 1.0, 0.0), -0.7, 1e-12);
}

TEST(ClosingSpeed, CountsThePersonsVelocityAndThatTheyMayTurnIntoTheRobot) {
  const ClosingSpeedConfig c = on(1.0);  // person_accel_mps2 3
  for (const double receding : {-0.5, 0.0, 0.6, 1.4}) {
    const double v = core::max_closing_speed(0.5, receding, 1.4, c);
    ASSERT_GT(v, 0.0) << receding;
    EXPECT_NEAR(closed_in_a_stop(v, receding, 1.4, c), 0.5 - c.margin_m, 1e-9) << receding;
  }
  const double standing = core::max_closing_speed(0.5, 0.0, 0.0, c);
  // behind a person walking away at 1.4 m/s the robot may close faster than on one standing
  // (they would take 0.33 m to stop); beside one walking across, far slower (they may turn into
  // it); on one coming toward it, slower again
  EXPECT_GT(core::max_closing_speed(0.5, 1.4, 1.4, c), standing + 0.2);
  EXPECT_LT(core::max_closing_speed(0.5, 0.0, 1.4, c), 0.6 * standing);
  EXPECT_LT(core::max_closing_speed(0.5, -0.5, 1.4, c), core::max_closing_speed(0.5, 0.0, 1.4, c));
  // a person coming fast and close: no closing speed at all (and never a negative one)
  EXPECT_DOUBLE_EQ(core::max_closing_speed(0.15, -1.5, 1.5, c), 0.0);
}

TEST(ClosingSpeed, SlowsOnlyThePartTowardThePerson) {
  const ClosingSpeedConfig c = on(1.0);
  const auto r = core::limit_closing_speed(ahead(0.3, c), {0, 0}, Twist{1.5, 0.4, 0}, c, kLimits);
  ASSERT_TRUE(r.limited);
  EXPECT_NEAR(r.gap_m, 0.3, 1e-12);
  EXPECT_NEAR(r.u.vx, core::max_closing_speed(0.3, 0.0, 0.0, c), 1e-12);
  EXPECT_DOUBLE_EQ(r.u.vy, 0.4) << "the sideways part does not close on them";
  EXPECT_DOUBLE_EQ(r.u.wz, 0.0);
}

TEST(ClosingSpeed, UsesThePersonsVelocityAlongTheLineBetweenThem) {
  const ClosingSpeedConfig c = on(1.0);
  const auto away =
      core::limit_closing_speed(ahead(0.3, c), {1.4, 0.3}, Twist{1.5, 0, 0}, c, kLimits);
  EXPECT_NEAR(away.max_closing_mps, core::max_closing_speed(0.3, 1.4, std::hypot(1.4, 0.3), c),
              1e-12);
  const auto toward =
      core::limit_closing_speed(ahead(0.3, c), {-0.5, 0.3}, Twist{1.5, 0, 0}, c, kLimits);
  EXPECT_NEAR(toward.max_closing_mps, core::max_closing_speed(0.3, -0.5, std::hypot(0.5, 0.3), c),
              1e-12);
  EXPECT_LT(toward.u.vx, away.u.vx);
}

TEST(ClosingSpeed, NeverTurnsACommandIntoMotionAway) {
  const ClosingSpeedConfig c = on(1.0);
  // touching, the person coming closer: the robot may stand, it is not pushed back
  const auto r = core::limit_closing_speed(ahead(0.0, c), {-1.0, 0}, Twist{0.8, 0, 0}, c, kLimits);
  ASSERT_TRUE(r.limited);
  EXPECT_NEAR(r.u.vx, 0.0, 1e-12);
  const auto still = core::limit_closing_speed(ahead(0.0, c), {-1.0, 0}, Twist{}, c, kLimits);
  EXPECT_FALSE(still.limited);
  // moving away is never limited
  const auto away = core::limit_closing_speed(ahead(0.0, c), {0, 0}, Twist{-0.5, 0, 0}, c, kLimits);
  EXPECT_FALSE(away.limited);
  EXPECT_DOUBLE_EQ(away.u.vx, -0.5);
}

TEST(ClosingSpeed, ACornerSwungTowardThePersonCounts) {
  const ClosingSpeedConfig c = on(1.0);
  // The person just left of the front-left corner (0.35, 0.30), the footprint's nearest point:
  // turning left moves that corner at w z x r = (-0.30 w, 0.35 w), toward them at 0.35 w.
  const Point2 person{0.35, 0.30 + c.person_radius_m + 0.12};
  const auto r = core::limit_closing_speed(person, {0, 0}, Twist{0, 0, 2.0}, c, kLimits);
  ASSERT_TRUE(r.limited);
  EXPECT_NEAR(r.closing_mps, 0.35 * 2.0, 1e-9);
  const double after = r.u.vy + 0.35 * r.u.wz;  // n = (0, 1)
  EXPECT_NEAR(after, r.max_closing_mps, 1e-9);
}

TEST(ClosingSpeed, TheVelocityBoxDoesNotUndoTheLimit) {
  const ClosingSpeedConfig c = on(1.0);
  // The person ahead-right of the front-right corner (0.35, -0.30), at 45 degrees: the least
  // change lowers vx and raises vy, here past its box at 1.5 m/s; the clipped command is then
  // scaled until it meets the limit.
  const double d = 0.11 + c.person_radius_m;
  const double n = 1.0 / std::sqrt(2.0);
  const Point2 person{0.35 + d * n, -0.30 - d * n};
  const auto r = core::limit_closing_speed(person, {0, 0}, Twist{1.8, 1.5, 0}, c, kLimits);
  ASSERT_TRUE(r.limited);
  EXPECT_LE(std::abs(r.u.vx), kLimits.vx);
  EXPECT_LE(std::abs(r.u.vy), kLimits.vy);
  // n = (1, -1) / sqrt 2; the corner moves at w z x r = (0.30 w, 0.35 w)
  const double closing = n * (r.u.vx + 0.30 * r.u.wz) - n * (r.u.vy + 0.35 * r.u.wz);
  EXPECT_NEAR(closing, r.max_closing_mps, 1e-9);
  EXPECT_LT(r.u.vy, 1.5) << "scaled after the box clipped vy";
}

// A robot driving at 1.5 m/s at a person standing 2 m ahead, braking at most 1.0 m/s^2 after
// a command latency of 20 ms: with the limit it stops short of them, without it it does not.
TEST(ClosingSpeed, ADrivingRobotStopsShortOfAStandingPerson) {
  auto run = [](double decel) {
    ClosingSpeedConfig c = on(decel);
    const double person_x = c.footprint.x_max_m + c.person_radius_m + 2.0;
    double x = 0.0, v = 1.5;
    double min_gap = 1e9;
    const double dt = 0.01;
    double queued = v, queued2 = v;  // 20 ms latency
    for (int i = 0; i < 400; ++i) {
      Twist want{1.5, 0, 0};
      if (decel > 0)
        want = core::limit_closing_speed({person_x - x, 0}, {0, 0}, want, c, kLimits).u;
      // what the base does: the command two periods ago, at most 1.0 m/s^2 of change
      const double target = queued2;
      queued2 = queued;
      queued = want.vx;
      v = std::clamp(target, v - 1.0 * dt, v + 1.0 * dt);
      x += v * dt;
      min_gap = std::min(min_gap, person_x - x - c.footprint.x_max_m - c.person_radius_m);
    }
    return min_gap;
  };
  EXPECT_GT(run(1.0), 0.0);
  EXPECT_LT(run(0.0), 0.0) << "without the limit the robot reaches them";
}

// follow_standoff_m: the nearest the robot may follow a walking person and still keep their pace
// under the limit. Checked against limit_closing_speed itself: a robot at the standoff moving
// with the person is not slowed; 2 cm nearer it is.
TEST(ClosingSpeed, TheFollowStandoffIsWhereTheLimitLetsTheRobotKeepPace) {
  const ClosingSpeedConfig c = on(1.0);
  const Point2 walking{1.0, 0.0};  // 1 m/s along the robot's +x (the robot behind them)
  const double standoff = core::follow_standoff_m({1.0, 0.0}, walking, c);
  // front face 0.35 + body 0.25 + margin 0.1 + reaction 0.05 + braking 0.5 - their stop 1/6
  EXPECT_NEAR(standoff, 0.35 + 0.25 + 0.10 + 0.05 + 0.5 - 1.0 / 6.0, 1e-6);
  const Twist keep_pace{1.0, 0.0, 0.0};
  EXPECT_FALSE(
      core::limit_closing_speed({standoff + 1e-6, 0.0}, walking, keep_pace, c, kLimits).limited);
  EXPECT_TRUE(
      core::limit_closing_speed({standoff - 0.02, 0.0}, walking, keep_pace, c, kLimits).limited);
  // Faster, farther: at 1.5 m/s the point behind needs ~1.5 m.
  const double fast = core::follow_standoff_m({1.0, 0.0}, {1.5, 0.0}, c);
  EXPECT_GT(fast, standoff + 0.4);
  EXPECT_FALSE(
      core::limit_closing_speed({fast + 1e-6, 0.0}, {1.5, 0.0}, {1.5, 0, 0}, c, kLimits).limited);
  // Diagonally behind (the person ahead-left, walking along +x): the box's front-left corner is
  // nearest, so the ray's distance is checked against the limit's own geometry (the limit
  // measures the person's recession along the nearest point's normal, the standoff along the
  // ray: within 3 cm).
  const Point2 diagonal{std::cos(0.5), std::sin(0.5)};
  const double d = core::follow_standoff_m(diagonal, walking, c);
  const Point2 at{diagonal.x_m * (d + 0.03), diagonal.y_m * (d + 0.03)};
  const Point2 near{diagonal.x_m * (d - 0.03), diagonal.y_m * (d - 0.03)};
  EXPECT_FALSE(core::limit_closing_speed(at, walking, keep_pace, c, kLimits).limited);
  EXPECT_TRUE(core::limit_closing_speed(near, walking, keep_pace, c, kLimits).limited);
  EXPECT_GT(d, standoff) << "the footprint's corner is nearer the person than its front face";
  // Beside a walking person, ahead of one (they walk toward the robot), beside a standing one,
  // or with the limit off: the limit never holds a pacing robot back there.
  EXPECT_DOUBLE_EQ(core::follow_standoff_m({0.0, 1.0}, walking, c), 0.0);
  EXPECT_DOUBLE_EQ(core::follow_standoff_m({-1.0, 0.0}, walking, c), 0.0);
  EXPECT_DOUBLE_EQ(core::follow_standoff_m({1.0, 0.0}, {0.0, 0.0}, c), 0.0);
  EXPECT_DOUBLE_EQ(core::follow_standoff_m({1.0, 0.0}, walking, ClosingSpeedConfig{}), 0.0);
}

TEST(Footprint, CoversItsBoxGrownAndItsCornerIsTheCircumscribedRadius) {
  const core::Footprint f;  // x -0.35 .. 0.35, y -0.30 .. 0.30
  EXPECT_TRUE(f.covers({0.35, -0.30}));
  EXPECT_FALSE(f.covers({0.36, 0.0}));
  EXPECT_TRUE(f.covers({0.36, 0.0}, 0.01 + 1e-12));
  EXPECT_FALSE(f.covers({0.0, -0.32}, 0.01));
  EXPECT_DOUBLE_EQ(f.circumscribed_radius_m(), std::hypot(0.35, 0.30));
  const core::Footprint off_centre{-0.2, 0.5, -0.1, 0.3};
  EXPECT_DOUBLE_EQ(off_centre.circumscribed_radius_m(), std::hypot(0.5, 0.3));
}
