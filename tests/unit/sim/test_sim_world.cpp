// The simulated world's parts: geometry, walks, recorded datasets, social force, the VLP-16
// emulation (decoded by the real decoder), the tracker emulation (read by the real person frame),
// the in-process datagram link, and the run metrics.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <sstream>

#include "amfitrack/amfiprot_codec.hpp"
#include "amfitrack/person_frame.hpp"
#include "core/perception/voxel_grid.hpp"
#include "firmware/config/config_loader.hpp"
#include "hal/net/datagram_queue.hpp"
#include "hal/sim_clock.hpp"
#include "sim/costmap_snapshot.hpp"
#include "sim/pedestrian_dataset.hpp"
#include "sim/run_metrics.hpp"
#include "sim/run_report.hpp"
#include "sim/scenario.hpp"
#include "sim/sim_amfitrack.hpp"
#include "sim/sim_run.hpp"
#include "sim/sim_vlp16.hpp"
#include "sim/sim_world.hpp"
#include "sim/social_force.hpp"
#include "vlp16/vlp16_codec.hpp"

using namespace std::chrono_literals;
using core::Point2;
using core::Pose2;

// ---- static world ------------------------------------------------------------------------------

TEST(StaticWorld, RaysHitTheFirstWallOrCircle) {
  sim::StaticWorld w;
  w.add_wall({5, -10}, {5, 10});
  w.add_circle({3, 0}, 0.5);
  auto d = w.ray({0, 0}, 1, 0, 100);
  ASSERT_TRUE(d);
  EXPECT_NEAR(*d, 2.5, 1e-9) << "the circle is in front of the wall";
  d = w.ray({0, 2}, 1, 0, 100);
  ASSERT_TRUE(d);
  EXPECT_NEAR(*d, 5.0, 1e-9);
  EXPECT_FALSE(w.ray({0, 0}, -1, 0, 100)) << "nothing behind";
  EXPECT_FALSE(w.ray({0, 2}, 1, 0, 4.0)) << "beyond max range";
  EXPECT_NEAR(w.distance({4, 3}), 1.0, 1e-9);
  EXPECT_NEAR(w.distance({3, 1}), 0.5, 1e-9);
}

TEST(StaticWorld, BoxesAreClosedPolygons) {
  sim::StaticWorld w;
  w.add_box({1, 1}, {2, 3});
  EXPECT_EQ(w.segments.size(), 4U);
  EXPECT_NEAR(*w.ray({0, 2}, 1, 0, 10), 1.0, 1e-9);
  EXPECT_NEAR(*w.ray({1.5, 0}, 0, 1, 10), 1.0, 1e-9);
  EXPECT_NEAR(*w.ray({1.5, 5}, 0, -1, 10), 2.0, 1e-9);
}

// ---- walks -----------------------------------------------------------------------------------

TEST(Walk, LegsAtTheirSpeedsWithSuddenTurns) {
  const sim::CornerLimits sudden{0.0, 0.0};
  const auto t = sim::walk({{{0, 0}}, {{4, 0}, 1.0}, {{4, 2}, 0.5}}, 1.0, 0.05, sudden);
  EXPECT_NEAR(t.end_s(), 1.0 + 4.0 + 4.0, 1e-9);
  auto p = t.pose_at(0.5);
  EXPECT_NEAR(p.x_m, 0.0, 1e-9) << "standing before the start";
  EXPECT_NEAR(p.theta_rad, 0.0, 1e-9) << "already facing the first leg";
  p = t.pose_at(3.0);
  EXPECT_NEAR(p.x_m, 2.0, 1e-6);
  EXPECT_NEAR(t.velocity_at(3.0).x_m, 1.0, 1e-6);
  p = t.pose_at(7.0);
  EXPECT_NEAR(p.x_m, 4.0, 1e-6);
  EXPECT_NEAR(p.y_m, 1.0, 1e-6);
  EXPECT_NEAR(p.theta_rad, std::numbers::pi / 2, 1e-6) << "turned at the corner";
  EXPECT_NEAR(t.velocity_at(7.0).y_m, 0.5, 1e-6);
  EXPECT_NEAR(t.pose_at(100).y_m, 2.0, 1e-9) << "stays at the end";
}

// Heading rate (rad/s) and lateral acceleration (m/s^2) at their largest along a walk, from its
// samples (as the simulator moves the person).
struct TurnPeaks {
  double turn_rate_radps = 0;
  double lateral_accel_mps2 = 0;
};
TurnPeaks turn_peaks(const sim::Trajectory& t) {
  TurnPeaks peaks;
  const auto& s = t.samples();
  for (size_t i = 1; i + 1 < s.size(); ++i) {
    const double dt = s[i + 1].t_s - s[i].t_s;
    if (dt < 1e-6) continue;
    const double rate =
        std::abs(core::wrap_angle(s[i + 1].pose.theta_rad - s[i].pose.theta_rad)) / dt;
    const double speed =
        std::hypot(s[i + 1].pose.x_m - s[i].pose.x_m, s[i + 1].pose.y_m - s[i].pose.y_m) / dt;
    peaks.turn_rate_radps = std::max(peaks.turn_rate_radps, rate);
    peaks.lateral_accel_mps2 = std::max(peaks.lateral_accel_mps2, rate * speed);
  }
  return peaks;
}

TEST(Walk, TurnsACornerOnAnArcAWalkingPersonCanWalk) {
  // 1.4 m/s into a 90-degree left corner: r = v^2 / 3 m/s^2 = 0.65 m, not on the spot.
  const sim::CornerLimits limits;  // 3 m/s^2, 3 rad/s
  const auto t = sim::walk({{{0, 0}}, {{8, 0}, 1.4}, {{8, 8}, 1.4}}, 0.0, 0.05, limits);
  const double r = 1.4 * 1.4 / limits.lateral_accel_mps2;
  const auto peaks = turn_peaks(t);
  EXPECT_LE(peaks.turn_rate_radps, limits.turn_rate_radps * 1.05);
  EXPECT_LE(peaks.lateral_accel_mps2, limits.lateral_accel_mps2 * 1.05);
  EXPECT_GT(peaks.turn_rate_radps, 1.4 / r * 0.9) << "and as tight as the limits allow";
  // The corner is cut by r(sqrt 2 - 1) at its closest, and the time is the arc's, not more.
  double closest = 1e9;
  for (const auto& s : t.samples())
    closest = std::min(closest, std::hypot(s.pose.x_m - 8.0, s.pose.y_m));
  EXPECT_NEAR(closest, r * (std::sqrt(2.0) - 1.0), 0.02);
  const double arc_time = r * std::numbers::pi / 2 / 1.4;
  EXPECT_NEAR(t.end_s(), (16.0 - 2 * r) / 1.4 + arc_time, 1e-6);
  EXPECT_NEAR(t.pose_at(t.end_s()).theta_rad, std::numbers::pi / 2, 1e-3) << "facing the new leg";
  // Mid-corner the heading is halfway round, not already turned.
  const double mid = (8.0 - r) / 1.4 + arc_time / 2;
  EXPECT_NEAR(t.pose_at(mid).theta_rad, std::numbers::pi / 4, 0.1);
}

TEST(Walk, ATurnBackOnShortLegsIsWalkedSlowerNotFaster) {
  // 170 degrees between 1 m legs: the arc that fits is tiny, so the turn rate limit sets the
  // time (a person turns round, they do not spin at 1.4 m/s).
  const sim::CornerLimits limits;
  const double back = 170.0 * std::numbers::pi / 180.0;
  const auto t = sim::walk({{{0, 0}}, {{1, 0}, 1.4}, {{1 + std::cos(back), std::sin(back)}, 1.4}},
                           0.0, 0.01, limits);
  const auto peaks = turn_peaks(t);
  EXPECT_LE(peaks.turn_rate_radps, limits.turn_rate_radps * 1.05);
  EXPECT_LE(peaks.lateral_accel_mps2, limits.lateral_accel_mps2 * 1.05);
  EXPECT_GE(t.end_s(), back / limits.turn_rate_radps) << "at least the time to turn round";
}

// The largest acceleration (m/s^2, both axes) between from_s and to_s of a walk's samples.
double peak_accel(const sim::Trajectory& t, double from_s, double to_s) {
  double peak = 0;
  const auto& s = t.samples();
  auto velocity = [&](size_t i) {  // over the interval ending at sample i
    const double dt = s[i].t_s - s[i - 1].t_s;
    return core::Point2{(s[i].pose.x_m - s[i - 1].pose.x_m) / dt,
                        (s[i].pose.y_m - s[i - 1].pose.y_m) / dt};
  };
  for (size_t i = 2; i < s.size(); ++i) {
    if (s[i].t_s < from_s || s[i].t_s > to_s) continue;
    const core::Point2 v1 = velocity(i);
    const core::Point2 v0 = velocity(i - 1);
    const double dt = 0.5 * (s[i].t_s - s[i - 2].t_s);
    peak = std::max(peak, std::hypot(v1.x_m - v0.x_m, v1.y_m - v0.y_m) / dt);
  }
  return peak;
}

TEST(Walk, SlowsIntoATurnBackAndSpeedsUpOutOfItAtTheCornersRate) {
  // 1.4 m/s out 6 m and back along nearly the same line: the arc that fits the legs is 2 cm
  // across and walked at a crawl (a turn on the spot, ~1 s at 3 rad/s). The walker slows into it
  // and speeds up out of it at 3 m/s^2, not in one step (and then walks back at the robot behind
  // them at 10+ m/s^2: seeds 20 and 60 of the random benchmark, twenty-second session).
  const std::vector<sim::Waypoint> out_and_back{{{0, 0}}, {{6, 0}, 1.4}, {{0, 0.1}, 1.4}};
  const sim::CornerLimits limits;
  ASSERT_GT(limits.speed_change_accel_mps2, 0.0);
  const auto t = sim::walk(out_and_back, 0.0, 0.01, limits);
  // Away from the start and end (from and to standing at once, as every benchmark walk).
  const double inside_from = 0.2;
  const double inside_to = t.end_s() - 0.2;
  EXPECT_LE(peak_accel(t, inside_from, inside_to), limits.speed_change_accel_mps2 * 1.05);
  // It still walks the whole way back, at its speed.
  EXPECT_NEAR(t.pose_at(t.end_s()).x_m, 0.0, 1e-6);
  EXPECT_NEAR(t.pose_at(t.end_s()).y_m, 0.1, 1e-6);
  EXPECT_NEAR(t.velocity_at(t.end_s() - 1.0).x_m, -1.4, 1e-3);
  // As before (0: at once), the same walk stops and turns back in a step.
  sim::CornerLimits sudden_speed = limits;
  sudden_speed.speed_change_accel_mps2 = 0.0;
  const auto old = sim::walk(out_and_back, 0.0, 0.01, sudden_speed);
  EXPECT_GT(peak_accel(old, inside_from, old.end_s() - 0.2), 10.0);
  EXPECT_LT(old.end_s(), t.end_s());
}

TEST(Walk, APauseAtACornerTurnsOnTheSpot) {
  const auto t = sim::walk({{{0, 0}}, {{4, 0}, 1.0, 1.0}, {{4, 2}, 1.0}}, 0.0);
  EXPECT_NEAR(t.pose_at(4.5).x_m, 4.0, 1e-9) << "stands at the corner itself";
  EXPECT_NEAR(t.pose_at(4.5).y_m, 0.0, 1e-9);
  EXPECT_NEAR(t.end_s(), 7.0, 1e-9);
}

TEST(Walk, StartsAndStopsAtTheGivenAccelerationWhenAsked) {
  sim::CornerLimits limits;
  limits.start_stop_accel_mps2 = 1.0;
  // 1.2 m/s on 6 m legs, 1 s at the far end, back: 0.72 m and 1.2 s for each speed ramp.
  const auto t = sim::walk({{{0, 0}}, {{6, 0}, 1.2, 1.0}, {{0, 0}, 1.2}}, 0.0, 0.01, limits);
  const double leg_s = 2 * 1.2 + (6.0 - 2 * 0.72) / 1.2;
  EXPECT_NEAR(t.end_s(), 2 * leg_s + 1.0, 1e-6);
  EXPECT_NEAR(t.pose_at(0.6).x_m, 0.5 * 0.6 * 0.6, 1e-3) << "speeding up: x = a t^2 / 2";
  EXPECT_NEAR(t.velocity_at(0.6).x_m, 0.6, 0.02);
  EXPECT_NEAR(t.velocity_at(3.0).x_m, 1.2, 1e-3) << "then at the leg's speed";
  EXPECT_NEAR(t.velocity_at(leg_s - 0.3).x_m, 0.3, 0.02) << "slowing down into the pause";
  EXPECT_NEAR(t.pose_at(leg_s + 0.5).x_m, 6.0, 1e-9) << "standing at the end";
  EXPECT_NEAR(t.velocity_at(leg_s + 1.0 + 0.6).x_m, -0.6, 0.02) << "and speeding up again";
  // No step anywhere faster than the ramp allows.
  const auto& s = t.samples();
  for (size_t i = 2; i < s.size(); ++i) {
    const double dt = s[i].t_s - s[i - 1].t_s;
    if (dt < 1e-6 || s[i - 1].t_s - s[i - 2].t_s < 1e-6) continue;
    const double v1 = (s[i].pose.x_m - s[i - 1].pose.x_m) / dt;
    const double v0 = (s[i - 1].pose.x_m - s[i - 2].pose.x_m) / (s[i - 1].t_s - s[i - 2].t_s);
    EXPECT_LE(std::abs(v1 - v0) / dt, 1.0 * 1.05 + 1e-6) << s[i].t_s;
  }
  // Without it (0, the default), the same walk starts and stops at once.
  const auto sudden = sim::walk({{{0, 0}}, {{6, 0}, 1.2, 1.0}, {{0, 0}, 1.2}}, 0.0, 0.01);
  EXPECT_NEAR(sudden.velocity_at(0.1).x_m, 1.2, 1e-6);
  EXPECT_NEAR(sudden.end_s(), 2 * 5.0 + 1.0, 1e-6);
}

TEST(Walk, EveryBuiltInPersonStartsAndStopsAsBrisklyAsAPersonCan) {
  // Scenarios 1-6, random walks (scenario 7) and dead ends: nowhere in the walk, its start and
  // its stop included, faster than 3 m/s^2 (up to the twenty-third session they went from
  // standing to walking speed in one 50 ms sample, 14-30 m/s^2, and stopped as suddenly).
  std::vector<sim::Scenario> scenarios;
  for (const char* name :
       {"open", "static_obstacle", "pedestrian_front_right", "corridor", "doorway", "crossing"}) {
    scenarios.push_back(*sim::make_scenario(name));
  }
  for (uint32_t seed = 1; seed <= 5; ++seed) {
    scenarios.push_back(*sim::make_scenario("random", seed));
    scenarios.push_back(*sim::make_scenario("dead_end", seed));
  }
  for (const sim::Scenario& s : scenarios) {
    const sim::Trajectory& t = s.person;
    EXPECT_LE(peak_accel(t, 0.0, t.end_s() + 1.0), sim::kBuiltInStartStopAccelMps2 * 1.05)
        << s.name;
    // Walking soon after the start, not a slow drift (the slowest built-in walk is 0.7 m/s).
    const double start_s = sim::kBuiltInStartDelayS;
    EXPECT_LT(std::hypot(t.velocity_at(start_s - 0.05).x_m, t.velocity_at(start_s - 0.05).y_m),
              1e-6)
        << s.name;
    EXPECT_GT(std::hypot(t.velocity_at(start_s + 0.8).x_m, t.velocity_at(start_s + 0.8).y_m), 0.65)
        << s.name;
  }
}

TEST(Scenario, CrossingPedestriansAreTimedToPassJustBehindThePerson) {
  // Scenario 6: each of the three walks across the person's path (y = 0) at their desired speed
  // when the person is 0.6 m past them, i.e. between the person and the robot 1 m behind (the
  // person's eased start puts them v / 2a behind one who started at full speed).
  const sim::Scenario s = *sim::make_scenario("crossing");
  ASSERT_EQ(s.pedestrians.size(), 3U);
  for (const sim::Pedestrian& p : s.pedestrians) {
    ASSERT_LT(p.position.y_m, 0.0);
    const double t_cross_s = -p.position.y_m / p.desired_speed_mps;
    EXPECT_NEAR(s.person.pose_at(t_cross_s).x_m, p.position.x_m + 0.6, 0.01) << p.position.x_m;
  }
}

TEST(Walk, HeadingIsKeptWhileStanding) {
  // Recorded positions jitter by a centimetre while a person stands: no spinning heading.
  std::vector<sim::TimedPose> s;
  s.reserve(20);
  for (int i = 0; i < 10; ++i)
    s.push_back({0.4 * i, {0.4 * i, 0.0, 0.0}});  // walking +x at 1 m/s
  for (int i = 10; i < 20; ++i)
    s.push_back({0.4 * i, {3.6 + (i % 2 == 0 ? 0.01 : -0.01), (i % 3) * 0.01, 0.0}});
  sim::set_headings_from_motion(s);
  for (const auto& p : s)
    EXPECT_NEAR(p.pose.theta_rad, 0.0, 1e-9) << "t=" << p.t_s;
}

namespace {
// The largest change of velocity (m/s) and of heading (rad) between consecutive steps of
// `step_s` over the track.
struct Jumps {
  double velocity_mps = 0;
  double heading_rad = 0;
};
Jumps largest_jumps(const sim::Trajectory& tr, double step_s) {
  Jumps j;
  const auto steps = static_cast<int>((tr.end_s() - tr.start_s()) / step_s);
  for (int i = 1; i + 1 < steps; ++i) {
    const double t = tr.start_s() + i * step_s;
    const Point2 a = tr.velocity_at(t - step_s);
    const Point2 b = tr.velocity_at(t);
    j.velocity_mps = std::max(j.velocity_mps, std::hypot(b.x_m - a.x_m, b.y_m - a.y_m));
    j.heading_rad = std::max(
        j.heading_rad,
        std::abs(core::wrap_angle(tr.pose_at(t).theta_rad - tr.pose_at(t - step_s).theta_rad)));
  }
  return j;
}
}  // namespace

TEST(SmoothTrack, PassesThroughEveryObservationAndTurnsACornerWithoutAJump) {
  // A 2.5 Hz track (as the ETH/UCY files) of a person walking 1.2 m/s east, then north.
  std::vector<sim::TimedPose> obs;
  for (int i = 0; i <= 6; ++i)
    obs.push_back({0.4 * i, {0.48 * i, 0.0, 0.0}});
  for (int i = 1; i <= 6; ++i)
    obs.push_back({0.4 * (6 + i), {2.88, 0.48 * i, 0.0}});
  sim::set_headings_from_motion(obs);
  const sim::Trajectory raw(obs);
  const sim::Trajectory smooth = sim::smooth_track(raw);
  ASSERT_EQ(smooth.samples().size(), 97U) << "every 50 ms over 4.8 s";
  for (const auto& o : obs) {
    EXPECT_NEAR(smooth.pose_at(o.t_s).x_m, o.pose.x_m, 1e-9) << "t=" << o.t_s;
    EXPECT_NEAR(smooth.pose_at(o.t_s).y_m, o.pose.y_m, 1e-9) << "t=" << o.t_s;
  }
  // On the straight legs the speed is the recorded one exactly; heading east, then north.
  EXPECT_NEAR(smooth.velocity_at(0.5).x_m, 1.2, 1e-9);
  EXPECT_NEAR(smooth.velocity_at(0.5).y_m, 0.0, 1e-9);
  EXPECT_NEAR(smooth.pose_at(1.0).theta_rad, 0.0, 1e-9);
  EXPECT_NEAR(smooth.pose_at(4.0).theta_rad, std::numbers::pi / 2, 1e-9);
  // Linear interpolation turns at once: the whole corner (90 deg, 1.7 m/s) in one 50 ms step.
  // The smooth track spreads it over the frames either side (it must still pass the corner's
  // observation: ~0.4 s for the turn, no step more than a third of it).
  const Jumps linear = largest_jumps(raw, 0.05);
  const Jumps smoothed = largest_jumps(smooth, 0.05);
  EXPECT_GT(linear.heading_rad, 1.5);
  EXPECT_GT(linear.velocity_mps, 1.6);
  EXPECT_LT(smoothed.heading_rad, linear.heading_rad / 3);
  EXPECT_LT(smoothed.velocity_mps, linear.velocity_mps / 4);
}

TEST(SmoothTrack, APersonWhoStopsStaysWhereSeenAndKeepsFacingTheirWay) {
  // Walking east at 1.2 m/s, then standing with the positions jittering by 2 cm. A smooth curve
  // that overshoots the stop would step back past it at a walking pace and turn the heading
  // round; this one does neither.
  std::vector<sim::TimedPose> obs;
  for (int i = 0; i <= 8; ++i)
    obs.push_back({0.4 * i, {0.48 * i, 0.0, 0.0}});
  for (int i = 9; i < 20; ++i)
    obs.push_back({0.4 * i, {3.84 + (i % 2 == 0 ? 0.02 : -0.02), (i % 3) * 0.02, 0.0}});
  const sim::Trajectory smooth = sim::smooth_track(sim::Trajectory(obs));
  for (const auto& s : smooth.samples()) {
    EXPECT_LE(s.pose.x_m, 3.87) << "t=" << s.t_s;
    EXPECT_NEAR(s.pose.theta_rad, 0.0, 1e-9) << "t=" << s.t_s;
  }
}

TEST(SmoothTrack, APersonUnseenForLongIsNotFilledInAndCostsNoSamples) {
  // Seen twice, then again a day later: the day is one straight piece (two samples), not
  // 1.7 million of them; the frames either side are walked as before.
  const sim::Trajectory observed(std::vector<sim::TimedPose>{{0.0, {0.0, 0.0, 0.0}},
                                                             {0.4, {0.4, 0.0, 0.0}},
                                                             {86400.0, {10.0, 0.0, 0.0}},
                                                             {86400.4, {10.4, 0.0, 0.0}}});
  const sim::Trajectory s = sim::smooth_track(observed);
  EXPECT_LT(s.samples().size(), 30U);
  EXPECT_NEAR(s.pose_at(0.2).x_m, 0.2, 1e-9);
  EXPECT_NEAR(s.pose_at(43200.2).x_m, 5.2, 1e-6) << "across the gap: straight";
  EXPECT_NEAR(s.pose_at(86400.2).x_m, 10.2, 1e-6);
  EXPECT_NEAR(s.end_s(), 86400.4, 1e-9);
}

TEST(SmoothTrack, UnderTwoObservationsOrTimesThatDoNotRiseAreHandled) {
  const sim::Trajectory one(std::vector<sim::TimedPose>{{1.0, {2.0, 3.0, 0.5}}});
  EXPECT_EQ(sim::smooth_track(one).samples().size(), 1U);
  // A repeated time keeps the first observation.
  const sim::Trajectory repeated(std::vector<sim::TimedPose>{{0.0, {0.0, 0.0, 0.0}},
                                                             {0.4, {0.4, 0.0, 0.0}},
                                                             {0.4, {9.0, 9.0, 0.0}},
                                                             {0.8, {0.8, 0.0, 0.0}}});
  const sim::Trajectory s = sim::smooth_track(repeated);
  EXPECT_NEAR(s.end_s(), 0.8, 1e-12);
  for (const auto& p : s.samples())
    EXPECT_NEAR(p.pose.y_m, 0.0, 1e-12) << "t=" << p.t_s;
}

// ---- recorded pedestrian datasets ---------------------------------------------------------------

TEST(PedestrianDataset, ParsesFramesIntoSecondsByTheGivenPeriod) {
  const std::string text =
      "0\t1.0\t1.0\t2.0\n"
      "0\t2.0\t5.0\t5.0\n"
      "10\t1.0\t1.4\t2.0\n"
      "20\t1.0\t1.8\t2.0\r\n"
      "# comment\n"
      "\n"
      "20\t2.0\t5.0\t5.4\n";
  const auto r = sim::parse_pedestrian_dataset(text, 0.4);
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_EQ(r.data.rows, 5U);
  EXPECT_EQ(r.data.frame_step, 10.0);
  ASSERT_EQ(r.data.people.size(), 2U);
  const auto& p1 = r.data.people.at(1);
  EXPECT_NEAR(p1.end_s(), 0.8, 1e-12);
  EXPECT_NEAR(p1.pose_at(0.2).x_m, 1.2, 1e-9) << "interpolated between rows";
  EXPECT_NEAR(p1.velocity_at(0.2).x_m, 1.0, 1e-9);
  const auto& p2 = r.data.people.at(2);
  EXPECT_NEAR(p2.end_s(), 0.8, 1e-12) << "a gap of one frame is bridged";
  EXPECT_NEAR(p2.pose_at(0.4).y_m, 5.2, 1e-9);
  EXPECT_EQ(sim::longest_walk(r.data), 1);
  EXPECT_EQ(sim::longest_walks(r.data, 5), (std::vector<int>{1, 2})) << "farthest first";
  EXPECT_EQ(sim::longest_walks(r.data, 1), (std::vector<int>{1}));
}

TEST(PedestrianDataset, BadInputIsAClearErrorWithTheLine) {
  auto r = sim::parse_pedestrian_dataset("0 1 2 3\n10 1 2\n", 0.4, "f.txt");
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.error, "f.txt:2: expected 4 columns 'frame id x y', got 3");
  r = sim::parse_pedestrian_dataset("0 1 2 abc\n", 0.4, "f.txt");
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.error, "f.txt:1: column 4 is not a number: 'abc'");
  r = sim::parse_pedestrian_dataset("0 1 2 nan\n", 0.4, "f.txt");
  EXPECT_FALSE(r.ok) << "not finite";
  r = sim::parse_pedestrian_dataset("0 1.5 2 3\n", 0.4, "f.txt");
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("whole number"), std::string::npos);
  r = sim::parse_pedestrian_dataset("", 0.4, "f.txt");
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.error, "f.txt: no observations");
  r = sim::parse_pedestrian_dataset("0 1 2 3\n", 0.0, "f.txt");
  EXPECT_FALSE(r.ok);
  r = sim::parse_pedestrian_dataset("0 1 2 3\n", 1e-300, "f.txt");
  EXPECT_FALSE(r.ok) << "a frame period that would make every walk infinitely fast";
  EXPECT_NE(r.error.find("frame period must be"), std::string::npos) << r.error;
  r = sim::parse_pedestrian_dataset("0 1 2 3\n10 1 1e300 3\n", 0.4, "f.txt");
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.error, "f.txt:2: position (1e300, 3) is more than 1000 km out: not metres");
  r = sim::parse_pedestrian_dataset("0 1 2 3\n1 1 2 3\n1e300 1 2 3\n", 0.4, "f.txt");
  EXPECT_FALSE(r.ok) << "frame values that span centuries";
  EXPECT_NE(r.error.find("not a recording"), std::string::npos) << r.error;
  r = sim::load_pedestrian_dataset("/nonexistent/file.txt", 0.4);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("cannot open"), std::string::npos);
}

TEST(PedestrianDataset, LoadsTheShippedRecordings) {
  for (const char* f : {"biwi_hotel.txt", "crowds_zara01.txt"}) {
    const auto r = sim::load_pedestrian_dataset(std::string(COMPANION_PEDESTRIANS) + "/" + f, 0.4);
    ASSERT_TRUE(r.ok) << r.error;
    EXPECT_GT(r.data.people.size(), 100U) << f;
    EXPECT_EQ(r.data.frame_step, 10.0) << f;
    std::string error;
    const auto s = sim::recorded_scenario(r.data, sim::longest_walk(r.data), &error);
    ASSERT_TRUE(s) << error;
    EXPECT_GT(s->replayed.size(), 3U) << f;
    EXPECT_GT(s->duration_s, 10.0);
    // Walked smoothly between the frames: sampled every 50 ms, through every observation.
    const auto& person = s->person.samples();
    ASSERT_GT(person.size(), 2U);
    EXPECT_NEAR(person[1].t_s - person[0].t_s, 0.05, 1e-9) << f;
    const auto& observed = r.data.people.at(sim::longest_walk(r.data)).samples();
    const double shift = person.front().t_s - observed.front().t_s;
    for (const auto& o : observed) {
      EXPECT_NEAR(s->person.pose_at(o.t_s + shift).x_m, o.pose.x_m, 1e-6) << f << " t=" << o.t_s;
      EXPECT_NEAR(s->person.pose_at(o.t_s + shift).y_m, o.pose.y_m, 1e-6) << f << " t=" << o.t_s;
    }
  }
}

// ---- social force ------------------------------------------------------------------------------

TEST(SocialForce, TwoWalkersHeadOnPassEachOtherAndArrive) {
  sim::Crowd crowd;
  sim::Pedestrian a;
  a.position = {0, 0};
  a.goals = {{10, 0}};
  sim::Pedestrian b = a;
  b.position = {10, 0.1};
  b.goals = {{0, 0.1}};
  crowd.add(a);
  crowd.add(b);
  sim::StaticWorld none;
  double closest = 1e9;
  for (int i = 0; i < 2000; ++i) {
    crowd.step(0.01, none, {});
    const auto& p = crowd.people();
    closest = std::min(closest, std::hypot(p[0].position.x_m - p[1].position.x_m,
                                           p[0].position.y_m - p[1].position.y_m));
  }
  EXPECT_GT(closest, 0.5) << "they step aside (radii 0.25 each)";
  EXPECT_TRUE(crowd.people()[0].arrived());
  EXPECT_TRUE(crowd.people()[1].arrived());
}

TEST(SocialForce, WallsRepelAndForcesFromBehindCountHalf) {
  sim::Crowd crowd;
  sim::StaticWorld w;
  w.add_wall({-10, 0.5}, {10, 0.5});
  const Point2 f = crowd.wall_force({0, 0}, {1, 0}, w);
  EXPECT_NEAR(f.x_m, 0.0, 1e-9);
  EXPECT_NEAR(f.y_m, -10.0 / 0.2 * std::exp(-0.5 / 0.2), 1e-9) << "U0/R exp(-d/R), away";
  // A standing person 1 m ahead vs 1 m behind: the same magnitude, behind weighted 0.5.
  const sim::MovingBody ahead{{1, 0}, {0, 0}, 0.25};
  const sim::MovingBody behind{{-1, 0}, {0, 0}, 0.25};
  const Point2 fa = crowd.person_force({0, 0}, 0.0, {1, 0}, ahead);
  const Point2 fb = crowd.person_force({0, 0}, 0.0, {1, 0}, behind);
  EXPECT_LT(fa.x_m, 0.0) << "pushed back";
  EXPECT_GT(fb.x_m, 0.0) << "pushed forward";
  EXPECT_NEAR(fb.x_m, -0.5 * fa.x_m, 1e-6);
  // V0/sigma exp(-b/sigma) with b the distance between the surfaces for a standing person.
  EXPECT_NEAR(-fa.x_m, 2.1 / 0.3 * std::exp(-(1.0 - 0.25) / 0.3), 1e-4);
  const Point2 wide = crowd.person_force({0, 0}, 0.3, {1, 0}, ahead);
  EXPECT_NEAR(-wide.x_m, 2.1 / 0.3 * std::exp(-(1.0 - 0.25 - 0.3) / 0.3), 1e-4)
      << "the walker's own radius counts too";
}

TEST(SocialForce, AWalkerGoesAroundAStandingRobotWithoutTouchingIt) {
  // The robot is seen at its size (0.45 m): with centre distances (Helbing & Molnar's points) a
  // walker leaned into it until the centres were ~0.3 m apart, i.e. through its body.
  for (const double offset_m : {0.05, 0.2, 0.4}) {
    sim::Crowd crowd;
    sim::Pedestrian p;
    p.position = {0, offset_m};
    p.velocity = {1.2, 0};
    p.radius_m = 0.3;
    p.goals = {{10, offset_m}};
    crowd.add(p);
    const sim::MovingBody robot{{5, 0}, {0, 0}, 0.45};
    double closest_gap_m = 1e9;
    for (int i = 0; i < 1500; ++i) {
      crowd.step(0.01, sim::StaticWorld{}, std::span<const sim::MovingBody>(&robot, 1));
      const auto& q = crowd.people()[0];
      closest_gap_m = std::min(closest_gap_m, std::hypot(q.position.x_m - 5, q.position.y_m) -
                                                  p.radius_m - robot.radius_m);
    }
    EXPECT_GT(closest_gap_m, 0.05) << "offset " << offset_m;
    EXPECT_TRUE(crowd.people()[0].arrived()) << "offset " << offset_m << ": and goes on";
  }
}

TEST(SocialForce, ALoopingWalkerWhoseGoalsAreAllWhereTheyStandDoesNotHangTheStep) {
  // The random scenario's walkers go to a random point and back, for ever; when that point falls
  // within goal_radius of the start, both goals are "reached" where they stand. The step used to
  // cycle through them for ever (a whole benchmark hung on one such seed).
  sim::Crowd crowd;
  sim::Pedestrian p;
  p.position = {1, 1};
  p.goals = {{1.05, 1.0}, {1, 1}};
  p.loop = true;
  crowd.add(p);
  for (int i = 0; i < 100; ++i)
    crowd.step(0.01, sim::StaticWorld{}, {});
  EXPECT_LT(std::hypot(crowd.people()[0].position.x_m - 1, crowd.people()[0].position.y_m - 1), 0.3)
      << "they stay about where they are";
}

TEST(SocialForce, SpeedIsCappedAt1_3TimesTheDesired) {
  sim::Crowd crowd;
  sim::Pedestrian p;
  p.velocity = {5, 0};
  p.desired_speed_mps = 1.0;
  p.goals = {{100, 0}};
  crowd.add(p);
  crowd.step(0.01, sim::StaticWorld{}, {});
  EXPECT_NEAR(std::hypot(crowd.people()[0].velocity.x_m, crowd.people()[0].velocity.y_m), 1.3,
              1e-9);
}

// ---- VLP-16 emulation, read by the real decoder -----------------------------------------------

TEST(SimVlp16, PacketsAtTheRealRateWithTheAzimuthAdvancingAt10Hz) {
  sim::SimVlp16 lidar;
  sim::StaticWorld w;
  std::vector<std::pair<vlp16::RawDataPacket, hal::Nanos>> got;
  auto sink = [&](std::span<const uint8_t> bytes, hal::Nanos at) {
    vlp16::RawDataPacket p;
    ASSERT_EQ(vlp16::parse_data_packet(bytes, p), vlp16::DecodeError::kNone);
    got.emplace_back(p, at);
  };
  const auto still = [](hal::Nanos) { return Pose2{}; };
  for (int ms = 0; ms <= 1000; ms += 5)
    lidar.step(hal::Nanos(std::chrono::milliseconds(ms)), w, {}, still, sink);
  EXPECT_NEAR(static_cast<double>(got.size()), 1e6 / sim::SimVlp16::kPacketUs, 1.0) << "754/s";
  for (size_t i = 1; i < got.size(); ++i) {
    const int step =
        (got[i].first.blocks[0].azimuth - got[i - 1].first.blocks[0].azimuth + 36000) % 36000;
    EXPECT_NEAR(step, 1327.104 * 0.36, 1.0) << i;  // 0.01 degree per packet at 600 rpm
    EXPECT_NEAR(got[i].first.timestamp_us - got[i - 1].first.timestamp_us, 1327.104, 1.0) << i;
    EXPECT_LE(got[i].second.count() - got[i - 1].second.count(), 1327105);
  }
}

TEST(SimVlp16, AWallAheadDecodesAtItsDistanceAndTheGroundBelowTheSensor) {
  sim::SimVlp16Config cfg;
  cfg.range_noise_m = 0.0;
  sim::SimVlp16 lidar(cfg);
  sim::StaticWorld w;
  w.add_wall({5.1, -20}, {5.1, 20});  // 5 m ahead of the sensor (mounted 0.10 m ahead)
  std::vector<vlp16::Point> pts(vlp16::kReturnsPerPacket);
  int wall = 0, ground = 0, behind = 0;
  auto sink = [&](std::span<const uint8_t> bytes, hal::Nanos) {
    vlp16::RawDataPacket p;
    ASSERT_EQ(vlp16::parse_data_packet(bytes, p), vlp16::DecodeError::kNone);
    const size_t n = vlp16::decode_points(p, {}, pts);
    for (size_t i = 0; i < n; ++i) {
      const double x = pts[i].x_m, y = pts[i].y_m, z = pts[i].z_m;
      const auto& q = pts[i];
      if (std::abs(y) < 1.0 && x > 0) {
        if (z > -0.44) {
          EXPECT_NEAR(q.x_m, 5.0, 0.02) << "laser " << int(q.laser);
          ++wall;
        } else {
          EXPECT_NEAR(q.z_m, -0.45, 0.01) << "the ground, 0.45 m below the sensor";
          ++ground;
        }
      }
      if (x < -0.5 && std::abs(y) < 1.0) ++behind;
    }
  };
  for (int ms = 5; ms <= 200; ms += 5) {
    lidar.step(
        hal::Nanos(std::chrono::milliseconds(ms)), w, {}, [](hal::Nanos) { return Pose2{}; }, sink);
  }
  EXPECT_GT(wall, 100);
  EXPECT_GT(ground, 100);
  EXPECT_GT(behind, 0) << "only ground behind";
}

TEST(SimVlp16, PeopleAreCylindersThatLowBeamsHitAndHighBeamsPass) {
  sim::SimVlp16Config cfg;
  cfg.range_noise_m = 0.0;
  sim::SimVlp16 lidar(cfg);
  const sim::StaticWorld empty;
  const std::vector<sim::Cylinder> person{{{2.1, 0.0}, 0.25, 1.0}};  // 1 m tall, 2 m ahead
  std::vector<vlp16::Point> pts(vlp16::kReturnsPerPacket);
  double max_z = -1;
  int hits = 0;
  auto sink = [&](std::span<const uint8_t> bytes, hal::Nanos) {
    vlp16::RawDataPacket p;
    (void)vlp16::parse_data_packet(bytes, p);
    const size_t n = vlp16::decode_points(p, {}, pts);
    for (size_t i = 0; i < n; ++i) {
      const double x = pts[i].x_m, y = pts[i].y_m, z = pts[i].z_m;
      if (std::abs(y) < 0.3 && x > 1.5 && x < 2.1 && z > -0.4) {
        ++hits;
        max_z = std::max(max_z, static_cast<double>(pts[i].z_m));
        EXPECT_NEAR(std::hypot(x - 2.0, y), 0.25, 0.01) << "on the surface (centre 2.0 m ahead)";
      }
    }
  };
  for (int ms = 5; ms <= 100; ms += 5) {
    lidar.step(
        hal::Nanos(std::chrono::milliseconds(ms)), empty, person,
        [](hal::Nanos) { return Pose2{}; }, sink);
  }
  EXPECT_GT(hits, 20);
  EXPECT_LE(max_z, 1.0 - 0.45 + 0.01) << "nothing above the person's head";
}

// ---- the world: tracker frames the daemon's person frame reads back ---------------------------

namespace {
// Every tracker frame of a world run for `ms` with the robot standing, read back through the
// real decoder and person frame, with the world's truth (base_link) when it was sent.
struct ReadBack {
  double t_s = 0;  // world time of the step that sent it
  amfitrack::PersonInBase person;
  Pose2 truth;
};
std::vector<ReadBack> read_back_tracker(const sim::Scenario& s, const sim::SimWorldConfig& cfg,
                                        int ms) {
  hal::SimClock clock;
  sim::SimWorld world(s, cfg, clock);
  auto link = world.take_tracker_link();
  const amfitrack::PersonFrame frame(cfg.tracker_extrinsics);
  std::vector<ReadBack> out;
  for (int t = 0; t <= ms; t += 5) {
    world.step(std::chrono::milliseconds(t));
    const Pose2 truth = world.robot_pose().inverse() * world.person_pose();
    while (auto p = link->receive()) {
      const auto parsed = amfitrack::decode_payload(*p);
      if (!parsed.payload) continue;
      const auto* m = std::get_if<amfitrack::SensorMeasurement>(&*parsed.payload);
      if (m == nullptr) continue;
      const auto person = frame.to_base(*m);
      if (person) out.push_back({world.time_s(), *person, truth});
    }
  }
  return out;
}

// A person walking a circle of `radius_m` about (cx, cy) at `speed_mps`, counter-clockwise.
sim::Scenario circle_walker(double cx, double cy, double radius_m, double speed_mps) {
  std::vector<sim::TimedPose> samples;
  const double rate = speed_mps / radius_m;
  for (int i = 0; i <= 200; ++i) {
    const double t = 0.05 * i;
    const double a = rate * t;
    samples.push_back({t, Pose2{cx + radius_m * std::cos(a), cy + radius_m * std::sin(a),
                                a + std::numbers::pi / 2}});
  }
  sim::Scenario s;
  s.name = "circle";
  s.person = sim::Trajectory(std::move(samples));
  s.robot_start = Pose2{0.0, 0.0, 0.4};
  return s;
}
}  // namespace

TEST(SimWorld, TrackerFramesPlaceThePersonWhereTheWorldHasThem) {
  sim::Scenario s;
  s.name = "t";
  s.person = sim::walk({{{2.0, 1.0}}, {{2.0, 5.0}, 1.0}}, 0.0);  // walking +y
  s.robot_start = Pose2{0.5, 0.5, 0.3};
  sim::SimWorldConfig cfg;
  cfg.tracker_extrinsics.source_xyz_m = {0.0, 0.0, 0.35};
  cfg.tracker_extrinsics.source_rpy_rad = {0.0, 0.0, std::numbers::pi};
  const auto frames = read_back_tracker(s, cfg, 500);
  EXPECT_NEAR(static_cast<double>(frames.size()), 60, 1) << "120 Hz, every frame a pose";
  ASSERT_GT(frames.size(), 55U);
  const ReadBack& f = frames[54];  // ~0.46 s
  EXPECT_NEAR(f.person.x_m, f.truth.x_m, 0.05);
  EXPECT_NEAR(f.person.y_m, f.truth.y_m, 0.05);
  EXPECT_NEAR(f.person.z_m, 1.0, 1e-3);
  EXPECT_NEAR(core::wrap_angle(f.person.heading_rad - f.truth.theta_rad), 0.0, 1e-3);
}

TEST(SimWorld, TheWornSensorsGyroReadsThePersonsTurnRateInItsOwnAxes) {
  // 1 m/s round a 2 m circle: 0.5 rad/s. The sensor is worn on its side (rolled 90 degrees), so
  // the turn is about its y axis: the person frame must rotate it back to base_link's z.
  const sim::Scenario s = circle_walker(4.0, 0.0, 2.0, 1.0);
  sim::SimWorldConfig cfg;
  cfg.tracker_extrinsics.sensor_in_body_rpy_rad = {std::numbers::pi / 2, 0.0, 0.0};
  const auto frames = read_back_tracker(s, cfg, 2000);
  ASSERT_GT(frames.size(), 200U);
  for (size_t i = 12; i < frames.size(); ++i) {  // from 0.1 s (the first step has no rate)
    EXPECT_NEAR(frames[i].person.yaw_rate_radps, 0.5, 0.002) << "frame " << i;
    EXPECT_NEAR(core::wrap_angle(frames[i].person.heading_rad - frames[i].truth.theta_rad), 0.0,
                1e-3);
  }
}

TEST(SimWorld, TheWornSensorSwaysWithTheGaitAndItsGyroWithIt) {
  // Walking straight at 1.4 m/s: one 1.4 m stride a second, the sensor's yaw +-0.07 rad about
  // the walking heading and its gyro the sway's rate, 0.07 * 2 pi = 0.44 rad/s at its peak.
  sim::Scenario s;
  s.name = "straight";
  s.person = sim::walk({{{2.0, -3.0}}, {{2.0, 20.0}, 1.4}}, 0.0, 0.05, {});
  s.robot_start = Pose2{0.0, 0.0, 0.0};
  sim::SimWorldConfig cfg;
  cfg.person_sway_rad = 0.07;
  const auto frames = read_back_tracker(s, cfg, 3000);
  ASSERT_GT(frames.size(), 300U);
  double sway_min = 1, sway_max = -1, rate_max = 0, heading_drift = 0;
  for (size_t i = 12; i < frames.size(); ++i) {
    const double sway = core::wrap_angle(frames[i].person.heading_rad - frames[i].truth.theta_rad);
    sway_min = std::min(sway_min, sway);
    sway_max = std::max(sway_max, sway);
    rate_max = std::max(rate_max, std::abs(frames[i].person.yaw_rate_radps));
    // The gyro, integrated frame to frame, turns the sensor as its yaw does.
    const double integrated =
        frames[i - 1].person.yaw_rate_radps * (frames[i].t_s - frames[i - 1].t_s);
    const double turned =
        core::wrap_angle(frames[i].person.heading_rad - frames[i - 1].person.heading_rad);
    heading_drift = std::max(heading_drift, std::abs(turned - integrated));
  }
  EXPECT_NEAR(sway_max, 0.07, 0.003);
  EXPECT_NEAR(sway_min, -0.07, 0.003);
  EXPECT_NEAR(rate_max, 0.07 * 2 * std::numbers::pi, 0.01);
  EXPECT_LT(heading_drift, 0.001) << "the gyro and the yaw tell one story";

  // Without sway the sensor faces the walking heading and its gyro reads nothing.
  cfg.person_sway_rad = 0.0;
  for (const ReadBack& f : read_back_tracker(s, cfg, 1000)) {
    EXPECT_NEAR(core::wrap_angle(f.person.heading_rad - f.truth.theta_rad), 0.0, 1e-3);
    EXPECT_NEAR(f.person.yaw_rate_radps, 0.0, 1e-3);
  }
}

TEST(SimAmfitrack, GyroBiasAndNoiseLeaveThePoseNoiseAsItWas) {
  sim::SimAmfitrackConfig quiet;
  quiet.position_noise_m = 0.01;
  quiet.heading_noise_rad = 0.02;
  sim::SimAmfitrackConfig noisy = quiet;
  noisy.gyro_noise_dps = 1.0;
  noisy.gyro_bias_dps = {0, 0, 2.0};
  sim::SimAmfitrack a(quiet);
  sim::SimAmfitrack b(noisy);
  a.set_gyro_dps({0, 0, 10.0});
  b.set_gyro_dps({0, 0, 10.0});
  auto la = a.host_link();
  auto lb = b.host_link();
  double sum = 0, sum2 = 0;
  int n = 0;
  for (int ms = 0; ms <= 10000; ms += 5) {
    a.step(std::chrono::milliseconds(ms));
    b.step(std::chrono::milliseconds(ms));
    while (auto pa = la->receive()) {
      auto pb = lb->receive();
      ASSERT_TRUE(pb);
      const auto da = amfitrack::decode_payload(*pa);
      const auto db = amfitrack::decode_payload(*pb);
      if (!da.payload || !db.payload) continue;
      const auto* ma = std::get_if<amfitrack::SensorMeasurement>(&*da.payload);
      const auto* mb = std::get_if<amfitrack::SensorMeasurement>(&*db.payload);
      if (ma == nullptr || mb == nullptr) continue;
      EXPECT_EQ(ma->position_m, mb->position_m);
      EXPECT_EQ(ma->quaternion_xyzw, mb->quaternion_xyzw);
      EXPECT_NEAR(ma->gyro_dps[2], 10.0, 0.04);  // the wire's 0.07 dps steps
      sum += mb->gyro_dps[2] - 10.0;
      sum2 += (mb->gyro_dps[2] - 10.0) * (mb->gyro_dps[2] - 10.0);
      ++n;
    }
  }
  ASSERT_GT(n, 1000);
  const double bias = sum / n;
  EXPECT_NEAR(bias, 2.0, 0.1);
  EXPECT_NEAR(std::sqrt(sum2 / n - bias * bias), 1.0, 0.1);
}

namespace {
// The world run with the robot standing (no commands: the base stays put) until `until_ms`:
// the least clearance between its footprint and anyone, and where everyone is then.
struct StandingRobotRun {
  double least_clearance_m = 1e9;
  Pose2 person;
  std::vector<Point2> pedestrians;
};
StandingRobotRun run_beside_standing_robot(const sim::Scenario& s, const sim::SimWorldConfig& cfg,
                                           int until_ms) {
  hal::SimClock clock;
  sim::SimWorld world(s, cfg, clock);
  StandingRobotRun r;
  for (int ms = 0; ms <= until_ms; ms += 5) {
    world.step(std::chrono::milliseconds(ms));
    r.least_clearance_m = std::min(r.least_clearance_m, world.footprint_clearance_people());
  }
  r.person = world.person_pose();
  r.pedestrians = world.pedestrian_positions();
  return r;
}
}  // namespace

TEST(SimWorld, ThePersonDoesNotWalkIntoAStandingRobotButPastItAndBackOntoTheirPath) {
  // The robot stands on the person's scripted line.
  sim::Scenario s;
  s.name = "t";
  s.person = sim::walk({{{0.0, 0.0}}, {{5.0, 0.0}, 1.0}}, 0.0);
  s.robot_start = Pose2{2.0, 0.0, 0.0};
  sim::SimWorldConfig cfg;
  const StandingRobotRun avoids = run_beside_standing_robot(s, cfg, 9000);
  EXPECT_GT(avoids.least_clearance_m, 0.04) << "kept the contact margin (0.05 m)";
  EXPECT_NEAR(avoids.person.x_m, 5.0, 0.02) << "back on the script's end point";
  EXPECT_NEAR(avoids.person.y_m, 0.0, 0.02);
  cfg.person_avoids_robot = false;
  EXPECT_EQ(run_beside_standing_robot(s, cfg, 9000).least_clearance_m, 0.0)
      << "the scripted walk alone goes through the robot";
}

namespace {
// A recorded pedestrian `recording` beside the standing robot (the followed person far away),
// until `until_ms`: with replayed_avoid_robot (the default) they keep the contact margin and end
// at `end`, back on their recording; without it the recording alone touches the robot.
void expect_recorded_walker_clears_standing_robot(const sim::Trajectory& recording, int until_ms,
                                                  Point2 end) {
  sim::Scenario s;
  s.name = "t";
  s.person = sim::walk({{{0.0, 10.0}}, {{5.0, 10.0}, 1.0}}, 0.0);
  s.replayed.push_back(recording);
  s.robot_start = Pose2{2.0, 0.0, 0.0};
  sim::SimWorldConfig cfg;
  const StandingRobotRun avoid = run_beside_standing_robot(s, cfg, until_ms);
  EXPECT_GT(avoid.least_clearance_m, 0.04) << "kept the contact margin (0.05 m)";
  ASSERT_EQ(avoid.pedestrians.size(), 1U);
  EXPECT_NEAR(avoid.pedestrians[0].x_m, end.x_m, 0.02) << "back on the recording";
  EXPECT_NEAR(avoid.pedestrians[0].y_m, end.y_m, 0.02);
  cfg.replayed_avoid_robot = false;
  EXPECT_EQ(run_beside_standing_robot(s, cfg, until_ms).least_clearance_m, 0.0)
      << "the recording alone touches the robot";
}
}  // namespace

TEST(SimWorld, ARecordedPedestrianDoesNotWalkIntoAStandingRobotEither) {
  // A recording straight through where the robot stands: they walk round it, as a person does,
  // and back onto their recording's end (only the old replay walks through it).
  expect_recorded_walker_clears_standing_robot(
      sim::walk({{{0.0, 0.0}}, {{5.0, 0.0}, 1.0, 4.0}}, 0.0), 8500, {5.0, 0.0});  // ends at 9 s
}

TEST(SimWorld, ARecordedPedestrianFirstSeenWhereTheRobotStandsAppearsClearOfIt) {
  // The recording starts at 1 s inside the standing robot's footprint (a person entering the
  // camera's view there): they appear just clear of it and walk back onto their recording.
  expect_recorded_walker_clears_standing_robot(
      sim::walk({{{2.1, 0.1}}, {{2.1, 4.0}, 1.0, 2.0}}, 1.0), 6000, {2.1, 4.0});  // ends at 6.9 s
}

// ---- the in-process datagram link ---------------------------------------------------------------

TEST(DatagramQueue, DeliversWhatHasArrivedByNowAndCountsOverflow) {
  hal::DatagramQueue q(3);
  const std::array<uint8_t, 2> a{1, 2};
  q.push(a, hal::Nanos(10));
  q.push(a, hal::Nanos(20));
  q.push(a, hal::Nanos(30));
  q.push(a, hal::Nanos(40));  // over capacity
  std::vector<int64_t> seen;
  q.drain(100, hal::Nanos(25), [&](const hal::UdpDatagram& d) {
    seen.push_back(d.stamp.count());
    EXPECT_EQ(d.bytes.size(), 2U);
  });
  EXPECT_EQ(seen, (std::vector<int64_t>{10, 20})) << "not the one arriving at 30";
  EXPECT_EQ(q.stats().kernel_drops, 1U);
  EXPECT_EQ(q.stats().datagrams, 2U);
  q.drain(100, hal::Nanos(100),
          [&](const hal::UdpDatagram& d) { seen.push_back(d.stamp.count()); });
  EXPECT_EQ(seen.size(), 3U);
}

// ---- run metrics -------------------------------------------------------------------------------

TEST(RunMetrics, UncomfortableTimeFarFailureAndCollision) {
  sim::RunMetricsRecorder r;
  sim::DaemonView v;
  v.active = true;
  const Pose2 person{0, 0, 0};
  // 1 s at 0.3 m (intimate zone, inside the ellipse), then 6 s at 2.5 m behind.
  double t = 0;
  for (int i = 0; i < 100; ++i, t += 0.01)
    r.record(t, 0.01, Pose2{-0.3, 0, 0}, person, {}, 5.0, 1.0, v);
  for (int i = 0; i < 600; ++i, t += 0.01)
    r.record(t, 0.01, Pose2{-2.5, 0, 0}, person, {}, 5.0, 1.0, v);
  auto m = r.finish();
  EXPECT_NEAR(m.uncomfortable_s, 1.0, 0.011);
  EXPECT_NEAR(m.inside_ellipse_s, 1.0, 0.011);
  EXPECT_FALSE(m.success);
  EXPECT_NE(m.failure.find("from the person for 5 s"), std::string::npos) << m.failure;
  EXPECT_FALSE(m.collision);
  EXPECT_EQ(m.failure_kind, sim::FailureKind::kLost) << "names the person, but is no collision";
  EXPECT_NEAR(m.side_time_s[4], 7.0, 0.02) << "behind";

  sim::RunMetricsRecorder c;
  c.record(0.0, 0.01, Pose2{-1, 0, 0}, person, {}, 0.5, 1.0, v);
  c.record(0.01, 0.01, Pose2{-1, 0, 0}, person, {}, 0.0, 1.0, v);
  m = c.finish();
  EXPECT_TRUE(m.collision);
  EXPECT_FALSE(m.success);
  EXPECT_NE(m.failure.find("obstacle"), std::string::npos);
  EXPECT_EQ(m.failure_kind, sim::FailureKind::kHitObstacle);

  // Touching people: the nearer centre names who (the tables count the kinds).
  sim::RunMetricsRecorder pedestrian;
  pedestrian.record(0.0, 0.01, Pose2{-1, 0, 0}, person, {{-1.0, 0.5}}, 5.0, 0.0, v);
  EXPECT_NE(pedestrian.finish().failure.find("collision with a pedestrian"), std::string::npos)
      << pedestrian.finish().failure;
  EXPECT_EQ(pedestrian.finish().failure_kind, sim::FailureKind::kHitPedestrian);
  sim::RunMetricsRecorder same;
  same.record(0.0, 0.01, Pose2{-0.5, 0, 0}, person, {{-1.5, 1.0}}, 5.0, 0.0, v);
  EXPECT_NE(same.finish().failure.find("collision with the person"), std::string::npos)
      << same.finish().failure;
  EXPECT_EQ(same.finish().failure_kind, sim::FailureKind::kHitPerson);
  EXPECT_STREQ(sim::to_string(sim::FailureKind::kHitPerson), "hit person");
}

// e = q^d - q^r in the robot frame, q^d the chosen point of W carried with the true person: a
// person who walks on moves q^d with them (the old metric kept q^d where the last selection
// put it, in the daemon's odometry).
TEST(RunMetrics, TrackingErrorIsTheChosenPointOnThePersonNowInTheRobotFrame) {
  sim::DaemonView v;
  v.active = true;
  v.has_goal = true;
  v.goal_in_person = Pose2{-1.0, 0.0, 0.1};  // 1 m behind them, turned 0.1 rad left
  const Pose2 robot{1, 1, std::numbers::pi / 2};
  sim::RunMetricsRecorder r;
  for (int i = 0; i < 10; ++i)  // q^d 0.3 m ahead of the robot
    r.record(0.01 * i, 0.01, robot, Pose2{1, 2.3, std::numbers::pi / 2}, {}, 5.0, 5.0, v);
  const auto m = r.finish();
  EXPECT_NEAR(m.rmse_ex_m, 0.3, 1e-9);
  EXPECT_NEAR(m.rmse_ey_m, 0.0, 1e-9);
  EXPECT_NEAR(m.rmse_etheta_rad, 0.1, 1e-9);
  ASSERT_FALSE(r.samples().empty());
  EXPECT_NEAR(r.samples().front().goal.y_m, 1.3, 1e-9);

  sim::RunMetricsRecorder walked;  // the person 0.2 m further on, the same choice
  for (int i = 0; i < 10; ++i)
    walked.record(0.01 * i, 0.01, robot, Pose2{1, 2.5, std::numbers::pi / 2}, {}, 5.0, 5.0, v);
  EXPECT_NEAR(walked.finish().rmse_ex_m, 0.5, 1e-9);
}

TEST(RunMetrics, SectorsNameTheSidesOfThePerson) {
  EXPECT_EQ(sim::sector_of(0.0), 0);
  EXPECT_STREQ(sim::sector_name(sim::sector_of(std::numbers::pi / 2)), "left");
  EXPECT_STREQ(sim::sector_name(sim::sector_of(std::numbers::pi)), "behind");
  EXPECT_STREQ(sim::sector_name(sim::sector_of(-std::numbers::pi)), "behind");
  EXPECT_STREQ(sim::sector_name(sim::sector_of(-std::numbers::pi / 2)), "right");
}

TEST(RunMetrics, SamplesCarryTheDaemonsCommandAndPlanCostsToDiagnoseATrial) {
  sim::RunMetricsRecorder r;
  sim::DaemonView v;
  v.active = true;
  v.cmd_vx = 0.75;
  v.cmd_vy = -0.25;
  v.cmd_wz = 0.5;
  v.has_person_estimate = true;
  v.person_est_theta = 1.25;
  v.person_est_yaw_rate = -0.125;
  v.tracking = true;
  v.plan_tracking = 12.5;
  v.plan_collision = 3000.0;
  v.plan_barrier = 0.0;
  r.record(0.0, 0.01, Pose2{-1, 0, 0}, Pose2{0, 0, 0}, {}, 5.0, 1.0, v);
  v.tracking = false;             // holding: no plan
  v.has_person_estimate = false;  // and no track
  r.record(0.2, 0.01, Pose2{-1, 0, 0}, Pose2{0, 0, 0}, {}, 5.0, 1.0, v);
  ASSERT_EQ(r.samples().size(), 2U);
  const std::string csv = sim::samples_csv(r.samples());
  EXPECT_NE(csv.find(",cmd_vx_mps,cmd_vy_mps,plan_tracking_cost,plan_collision_cost,"
                     "plan_barrier_cost,cmd_wz_radps,person_est_theta_rad,"
                     "person_est_yaw_rate_radps\n"),
            std::string::npos)
      << csv;
  EXPECT_NE(csv.find(",0.750,-0.250,12.5,3000.0,0.0,0.5000,1.2500,-0.1250\n"), std::string::npos)
      << csv;
  EXPECT_NE(csv.find(",0.750,-0.250,nan,nan,nan,0.5000,nan,nan\n"), std::string::npos) << csv;
}

TEST(RunMetrics, SamplesAreTakenAtTheConfiguredPeriod) {
  sim::MetricsConfig cfg;
  cfg.sample_period_s = 0.01;
  sim::RunMetricsRecorder r(cfg);
  for (int i = 0; i < 200; ++i) {  // one second of 5 ms world steps
    r.record(0.005 * i, 0.005, Pose2{-1, 0, 0}, Pose2{0, 0, 0}, {}, 5.0, 1.0, sim::DaemonView{});
  }
  ASSERT_EQ(r.samples().size(), 100U);
  EXPECT_NEAR(r.samples()[1].t_s - r.samples()[0].t_s, 0.01, 1e-9);
}

TEST(RunReport, WorldCsvListsEveryWallAndObstacleForThePlots) {
  sim::StaticWorld w;
  w.add_wall({0, -1}, {4, -1});
  w.add_box({1, 1}, {2, 1.5});  // four segments
  w.add_circle({3, 0.5}, 0.25);
  const std::string csv = sim::world_csv(w);
  EXPECT_EQ(csv.rfind("kind,a,b,c,d\nsegment,0.000,-1.000,4.000,-1.000\n", 0), 0U) << csv;
  EXPECT_NE(csv.find("\ncircle,3.000,0.500,0.250,\n"), std::string::npos) << csv;
  size_t segments = 0;
  for (size_t at = csv.find("\nsegment,"); at != std::string::npos;
       at = csv.find("\nsegment,", at + 1)) {
    ++segments;
  }
  EXPECT_EQ(segments, 5U) << csv;
  EXPECT_EQ(sim::world_csv(sim::StaticWorld{}), "kind,a,b,c,d\n");
}

// ---- costmap snapshots (companion-eval --costmap-at) ------------------------------------------

namespace {
// A wall across x = 1.5 m, |y| <= 0.6 m, in a 10 m map, scanned at each of `scans` (ascending);
// the map is built at the last.
core::Costmap wall_costmap(std::initializer_list<core::Nanos> scans = {1s}) {
  core::VoxelGridConfig gc;
  gc.size_xy_m = 10.0;
  core::VoxelGrid g(gc);
  g.recentre(1.5, 0);
  std::vector<core::Ray> rays;
  for (int k = 0; k <= 60; ++k) {  // every 2 cm
    rays.push_back({{1.5, -3.0, 3.0}, {1.5, -0.6 + 0.02 * k, 0.5}});
  }
  for (const core::Nanos t : scans)
    g.insert(rays, Pose2{30, 30, 0}, std::nullopt, t);
  core::Costmap m;
  m.build(g, core::CostmapConfig{}, *(scans.end() - 1));
  return m;
}

// The pixel of a snapshot image (costmap_pgm's layout) over the point (x, y); checks the header.
uint8_t pgm_pixel(const std::string& pgm, const core::Costmap& map, double x, double y) {
  const int n = map.cells();
  const std::string header = "P5\n" + std::to_string(n) + " " + std::to_string(n) + "\n255\n";
  EXPECT_EQ(pgm.compare(0, header.size(), header), 0);
  EXPECT_EQ(pgm.size(), header.size() + static_cast<size_t>(n) * static_cast<size_t>(n));
  const int i = static_cast<int>(std::floor((x - map.origin_x()) / map.resolution()));
  const int j = static_cast<int>(std::floor((y - map.origin_y()) / map.resolution()));
  const size_t row = static_cast<size_t>(n - 1 - j);  // the top row is the largest y
  return static_cast<uint8_t>(
      pgm.at(header.size() + row * static_cast<size_t>(n) + static_cast<size_t>(i)));
}
}  // namespace

TEST(CostmapSnapshot, IsAMapServerPgmWithTheTopRowTheLargestY) {
  const core::Costmap map = wall_costmap();
  const std::string pgm = sim::costmap_pgm(map);
  auto pixel = [&](double x, double y) { return pgm_pixel(pgm, map, x, y); };
  ASSERT_EQ(map.at(1.5, 0.0), core::kCostLethal);
  EXPECT_EQ(pixel(1.5, 0.0), 0) << "lethal is black";
  EXPECT_EQ(pixel(1.5, 3.0), 255) << "free is white";
  EXPECT_EQ(pixel(-2.0, 0.0), 255);
  // Inflation: grey between, darker nearer the wall.
  EXPECT_LT(pixel(1.5, 0.95), pixel(1.5, 1.2));
}

// The obstacle layer's ages: a wall seen at 1 s and again at 2.5 s is 1.5 s old in the map built
// then; no obstacle (free, or only inflated round one) is white.
TEST(CostmapSnapshot, AgeImageShowsHowLongEachObstacleCellHasStood) {
  const core::Costmap map = wall_costmap({1s, 2500ms});
  const std::string pgm = sim::costmap_age_pgm(map);
  ASSERT_EQ(map.at(1.5, 0.0), core::kCostLethal);
  const auto i = static_cast<int>(std::floor((1.5 - map.origin_x()) / map.resolution()));
  const auto j = static_cast<int>(std::floor((0.0 - map.origin_y()) / map.resolution()));
  ASSERT_TRUE(map.obstacle(i, j));
  EXPECT_NEAR(map.obstacle_age_s(i, j), 1.5, 1e-9);
  EXPECT_EQ(pgm_pixel(pgm, map, 1.5, 0.0), 254 - 30) << "1.5 s in 0.05 s steps";
  EXPECT_EQ(pgm_pixel(pgm, map, 1.5, 3.0), 255) << "free";
  EXPECT_EQ(pgm_pixel(pgm, map, 1.2, 0.0), 255) << "inflated round the wall, no obstacle";
  // A wall seen once, in the map built at that scan: a new obstacle, just off white.
  const core::Costmap fresh = wall_costmap();
  EXPECT_EQ(pgm_pixel(sim::costmap_age_pgm(fresh), fresh, 1.5, 0.0), 254);
}

TEST(CostmapSnapshot, YamlHasTheMapServerKeysAndWhatTheDaemonKnew) {
  const core::Costmap map = wall_costmap();
  sim::CostmapMarks m;
  m.t_s = 9.5;
  m.robot_odom = Pose2{0.5, 1.5, 0.25};
  m.has_goal = m.has_person = true;
  m.person_odom = Pose2{1, 0, 0};
  m.goal_odom = Pose2{1, 0.7, 0};
  m.tracking = true;
  m.plan_tracking = 5199.9;
  m.predicted_person = {Pose2{1, 0, 0}, Pose2{1.8, 0, 0}};
  m.predicted_goal = {Pose2{1, 0.7, 0}, Pose2{1.8, 0.7, 0}};
  const std::string y = sim::costmap_yaml(map, "snap.pgm", m);
  const std::vector<std::string> wanted = {
      "image: snap.pgm\n",
      "resolution: 0.05\n",
      fmt::format("origin: [{:.4f}, {:.4f}, 0.0]\n", map.origin_x(), map.origin_y()),
      "negate: 0\n",
      "occupied_thresh: 0.300\n",
      "t_s: 9.500\n",
      "robot: [0.5000, 1.5000, 0.2500]\n",
      "goal: [1.0000, 0.7000, 0.0000]\n",
      "predicted_goal: [[1.0000, 0.7000, 0.0000], [1.8000, 0.7000, 0.0000]]\n",
      "plan_cost: {tracking: 5199.9, collision: 0.0, barrier: 0.0}\n"};
  EXPECT_EQ(y.find("obstacle_ages"), std::string::npos) << "no age image named: no key";
  m.age_image = "snap-age.pgm";
  m.obstacle_settled_s = 1.0;
  EXPECT_NE(sim::costmap_yaml(map, "snap.pgm", m)
                .find("obstacle_ages: {image: snap-age.pgm, step_s: 0.05, settled_s: 1}\n"),
            std::string::npos);
  for (const std::string& want : wanted) {
    EXPECT_NE(y.find(want), std::string::npos) << want << " in\n" << y;
  }
  m.tracking = m.has_goal = m.has_person = false;
  const std::string holding = sim::costmap_yaml(map, "snap.pgm", m);
  EXPECT_NE(holding.find("goal: null\n"), std::string::npos) << holding;
  EXPECT_NE(holding.find("plan_cost: null\n"), std::string::npos) << holding;
}

TEST(CostmapSnapshot, ARunWritesOneAtEachTimeAsked) {
  const auto dir = std::filesystem::path(testing::TempDir()) / "companion-costmap-snapshots";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  sim::SimRunOptions o;
  o.config = *firmware::load_default_config().config;
  o.scenario = *sim::make_scenario("static_obstacle");
  o.duration_s = 2.5;
  o.costmap_at_s = {2.0, 1.5};
  o.costmap_stem = (dir / "trial").string();
  sim::run_simulation(o);
  for (const char* t : {"1.5", "2.0"}) {
    const auto stem = dir / (std::string("trial-t") + t);
    std::ifstream yaml(stem.string() + ".yaml");
    ASSERT_TRUE(yaml.good()) << stem;
    std::stringstream text;
    text << yaml.rdbuf();
    EXPECT_NE(text.str().find("image: trial-t" + std::string(t) + ".pgm"), std::string::npos);
    EXPECT_NE(text.str().find("obstacle_ages: {image: trial-t" + std::string(t) + "-age.pgm"),
              std::string::npos);
    for (const char* suffix : {".pgm", "-age.pgm"}) {
      std::ifstream pgm(stem.string() + suffix, std::ios::binary);
      ASSERT_TRUE(pgm.good()) << stem << suffix;
      std::string head(2, '\0');
      pgm.read(head.data(), 2);
      EXPECT_EQ(head, "P5");
    }
  }
}
