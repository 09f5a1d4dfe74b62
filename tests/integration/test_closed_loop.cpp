// The whole product in the simulated world, on the simulated clock: the real task table, the real
// drivers decoding the devices' real bytes (Scout Mini CAN frames, Amfiprot 0x1A frames, VLP-16
// packets ray cast from the world), the supervisor gating every command.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <numeric>

#include "core/policy/observation.hpp"
#include "firmware/config/config_loader.hpp"
#include "firmware/daemon.hpp"
#include "scout_mini/scout_codec.hpp"
#include "sim/pedestrian_dataset.hpp"
#include "sim/scenario.hpp"
#include "sim/sim_run.hpp"

using sim::SimRunOptions;

namespace {
firmware::DaemonConfig defaults() {
  return *firmware::load_default_config().config;
}

SimRunOptions scenario(const std::string& name) {
  SimRunOptions o;
  o.config = defaults();
  o.scenario = *sim::make_scenario(name);
  return o;
}

void print(const std::string& name, const sim::SimRunResult& r) {
  const auto& m = r.metrics;
  std::printf(
      "%s: %s %s | UT %.2f s, in ellipse %.2f s, active %.1f/%.1f s, rmse %.3f %.3f %.3f, "
      "min static %.2f m people %.2f m, person %.2f..%.2f m (mean %.2f), stops %llu, wall %.1f s\n",
      name.c_str(), m.success ? "SUCCESS" : "FAIL", m.failure.c_str(), m.uncomfortable_s,
      m.inside_ellipse_s, m.active_s, m.duration_s, m.rmse_ex_m, m.rmse_ey_m, m.rmse_etheta_rad,
      m.min_static_clearance_m, m.min_people_clearance_m, m.min_person_distance_m,
      m.max_person_distance_m, m.mean_person_distance_m, static_cast<unsigned long long>(m.stops),
      r.wall_s);
}

bool is_active(const firmware::Daemon& d) {
  const auto s = d.safety().read();
  return s && s->value.state == core::SafetyState::kActive;
}

double speed(sim::SimWorld& w) {
  const auto& v = w.base().velocity();
  return std::hypot(v.vx_mps, v.vy_mps) + std::abs(v.wz_radps);
}
}  // namespace

// ---- scenarios 1-6 of reference/evaluation.md: success = no collision, never lost ------------

class PaperScenario : public testing::TestWithParam<const char*> {};

TEST_P(PaperScenario, AccompaniesThePersonWithoutCollision) {
  const auto r = sim::run_simulation(scenario(GetParam()));
  print(GetParam(), r);
  EXPECT_FALSE(r.metrics.collision) << r.metrics.failure;
  EXPECT_TRUE(r.metrics.success) << r.metrics.failure;
  EXPECT_GT(r.metrics.active_s, 0.7 * (r.metrics.duration_s - 4.0)) << "moving most of the run";
  EXPECT_LT(r.metrics.uncomfortable_s, 1.0) << "hardly ever in the intimate zone";
}

INSTANTIATE_TEST_SUITE_P(Scenarios1To6, PaperScenario,
                         testing::Values("open", "static_obstacle", "pedestrian_front_right",
                                         "corridor", "doorway", "crossing"));

TEST(ClosedLoop, OpenSpaceKeepsThePersonWithinTheInteractionSpace) {
  const auto r = sim::run_simulation(scenario("open"));
  const auto& m = r.metrics;
  EXPECT_GT(m.tracking_s, 25.0);
  // Around the ellipse (a = 1.0, b = 0.7 m) the whole walk, sharp turns included.
  EXPECT_GT(m.mean_person_distance_m, 0.7);
  EXPECT_LT(m.mean_person_distance_m, 1.4);
  EXPECT_LT(m.longest_far_s, 2.0) << "never more than 2 m away for long";
  EXPECT_LT(m.rmse_ex_m, 0.5);
  EXPECT_LT(m.rmse_ey_m, 0.5);
}

TEST(ClosedLoop, APolicyFileInTheConfigurationChoosesThePoint) {
  // A policy whose logits do not depend on the observation and prefer point 16 (the person's
  // left); the objective (alpha < 0) keeps the robot straight behind in the open. With
  // policy.file set, the simulated daemon must choose the left point, as companiond would (the
  // closed loop once ran the objective whatever the file said).
  const int n = 64;
  core::PolicyFile p;
  p.layout_id = core::kObservationLayout;
  p.points = n;
  const auto in = static_cast<Eigen::Index>(core::observation_size(n));
  p.mean = Eigen::VectorXf::Zero(in);
  p.stddev = Eigen::VectorXf::Ones(in);
  core::DenseLayer layer;
  layer.weights = Eigen::MatrixXf::Zero(n, in);
  layer.bias = Eigen::VectorXf::Zero(n);
  layer.bias[16] = 10.0f;
  p.layers.push_back(layer);
  const std::string path = testing::TempDir() + "/left.policy";
  const auto bytes = core::encode_policy(p);
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()),
             static_cast<std::streamsize>(bytes.size()));

  auto o = scenario("open");
  o.duration_s = 15;
  std::array<int, 8> policy_sides{}, objective_sides{};
  auto count = [](const sim::SimRunResult& r, std::array<int, 8>& sides) {
    for (const auto& s : r.samples)
      if (s.t_s > 5 && s.side >= 0) ++sides[static_cast<size_t>(s.side)];
  };
  count(sim::run_simulation(o), objective_sides);
  o.config.policy.file = path;
  count(sim::run_simulation(o), policy_sides);
  const int total = std::accumulate(policy_sides.begin(), policy_sides.end(), 0);
  ASSERT_GT(total, 50);
  EXPECT_GT(policy_sides[2], total * 9 / 10) << "left of the person";
  EXPECT_GT(objective_sides[4],
            std::accumulate(objective_sides.begin(), objective_sides.end(), 0) / 2)
      << "behind without the file";
  // A file that does not load is an error, not a silent objective run.
  o.config.policy.file = testing::TempDir() + "/missing.policy";
  EXPECT_THROW(sim::run_simulation(o), std::runtime_error);
}

TEST(ClosedLoop, SwitchesSidesAroundAStaticObstacle) {
  // The robot starts behind-right; the box on the person's right (x 6..10) leaves no free point
  // there, so the chosen point moves to another side while passing it. With alpha = 1 (G pulled
  // toward the person's near side): the shipped alpha < 0 keeps the robot straight behind here,
  // where the box closes no point, so there would be no side to switch from.
  std::array<double, 8> before{}, passing{};
  auto o = scenario("static_obstacle");
  o.config.objective.alpha = 1.0;
  // And the random samples alone, the controller it was found with (with the guide samples the
  // robot starts toward straight behind sooner: on the right 48 % of the time before the box).
  o.config.mppi.guide_samples = false;
  o.script = [&](double, sim::SimWorld& w, firmware::Daemon& d) {
    const auto v = sim::daemon_view(d);
    if (!v.active || v.side < 0) return;
    const double x = w.person_pose().x_m;
    if (x > 1.0 && x < 5.0) before[static_cast<size_t>(v.side)] += 0.005;
    if (x > 7.0 && x < 9.5) passing[static_cast<size_t>(v.side)] += 0.005;
  };
  const auto r = sim::run_simulation(o);
  print("static_obstacle", r);
  EXPECT_FALSE(r.metrics.collision) << r.metrics.failure;
  const double right_before = before[5] + before[6] + before[7];
  const double right_passing = passing[5] + passing[6] + passing[7];
  EXPECT_GT(right_before, 0.5 * std::accumulate(before.begin(), before.end(), 0.0))
      << "on the right before the obstacle";
  EXPECT_LT(right_passing, 0.1 * std::accumulate(passing.begin(), passing.end(), 0.0))
      << "not on the right while passing it";
}

// ---- the watchdog: tracker confidence, silence, lidar, base -----------------------------------

TEST(ClosedLoop, LowTrackerConfidenceStopsWithinTheBoundAndResumesAfterTheHysteresis) {
  // A slow walk (0.5 m/s), so that the person is still within reach (supervisor.
  // person_max_distance_m) when the robot may move again.
  auto o = scenario("open");
  o.scenario.person = sim::walk({{{0, 0}}, {{20, 0}, 0.5}}, 4.0);
  o.duration_s = 14.0;
  const double drop_at = 8.0, good_again = 9.0;
  double stopped_at = -1, resumed_at = -1;
  o.script = [&](double t, sim::SimWorld& w, firmware::Daemon& d) {
    if (std::abs(t - drop_at) < 1e-9) w.tracker().set_quality(40);  // below quality_bad_below
    if (std::abs(t - good_again) < 1e-9) w.tracker().set_quality(230);
    if (t > drop_at && stopped_at < 0 && speed(w) == 0.0) stopped_at = t;
    if (t > good_again && resumed_at < 0 && is_active(d)) resumed_at = t;
    if (t > drop_at && t < good_again) {
      const auto s = d.safety().read();
      if (t > drop_at + 0.1) {
        EXPECT_EQ(s->value.reason, core::Reason::kTrackerConfidenceLow) << "t=" << t;
      }
    }
  };
  std::string final_status;
  auto observe = o.script;
  o.script = [&](double t, sim::SimWorld& w, firmware::Daemon& d) {
    observe(t, w, d);
    final_status = d.status_line();
  };
  const auto r = sim::run_simulation(o);
  const auto cfg = defaults();
  ASSERT_GT(stopped_at, 0) << "stopped";
  // The gate needs the frames, the supervisor one tick, the stop at most stop_max_time_ms.
  EXPECT_LE(stopped_at - drop_at,
            static_cast<double>(cfg.supervisor.stop_max_time_ms) / 1000.0 + 0.1);
  ASSERT_GT(resumed_at, 0) << "resumed; " << final_status;
  EXPECT_GE(resumed_at - good_again,
            static_cast<double>(cfg.supervisor.tracker_confidence_recover_ms) / 1000.0)
      << "not before the hysteresis";
  EXPECT_LE(resumed_at - good_again,
            static_cast<double>(cfg.supervisor.tracker_confidence_recover_ms) / 1000.0 + 0.5);
  EXPECT_FALSE(r.metrics.collision);
}

struct Fault {
  const char* name;
  std::function<void(sim::SimWorld&, bool on)> inject;
  core::Reason reason;
};

// gtest finds a test parameter's printer by this name.
void PrintTo(const Fault& f, std::ostream* os) {  // NOLINT(readability-identifier-naming)
  *os << f.name;
}

class InputFault : public testing::TestWithParam<Fault> {};

TEST_P(InputFault, StopsTheRobotAndNamesTheReason) {
  const Fault& f = GetParam();
  auto o = scenario("open");
  o.duration_s = 10.0;
  const double at = 7.0;  // walking by then
  bool moving_before = false;
  double stopped_at = -1;
  bool reason_seen = false;
  o.script = [&](double t, sim::SimWorld& w, firmware::Daemon& d) {
    if (t < at && speed(w) > 0.3) moving_before = true;
    if (std::abs(t - at) < 1e-9) f.inject(w, true);
    if (t > at && stopped_at < 0 && speed(w) == 0.0) stopped_at = t;
    if (t > at + 0.5) {
      const auto s = d.safety().read();
      if ((s->value.active_mask >> core::reason_index(f.reason) & 1U) != 0) reason_seen = true;
      EXPECT_FALSE(s->value.motion_allowed) << f.name << " t=" << t;
      const auto c = d.command().read();
      if (t > at + 2.0) {
        EXPECT_TRUE(c->value.is_zero()) << f.name << " t=" << t;
      }
    }
  };
  sim::run_simulation(o);
  EXPECT_TRUE(moving_before) << "the robot was moving before the fault";
  EXPECT_TRUE(reason_seen) << core::reason_name(f.reason);
  ASSERT_GT(stopped_at, 0) << "stopped";
  EXPECT_LE(stopped_at - at, 2.0);
}

INSTANTIATE_TEST_SUITE_P(
    Watchdog, InputFault,
    testing::Values(
        Fault{"tracker_silent", [](sim::SimWorld& w, bool on) { w.tracker().set_silent(on); },
              core::Reason::kTrackerSilent},
        Fault{"lidar_silent", [](sim::SimWorld& w, bool on) { w.set_lidar_silent(on); },
              core::Reason::kLidarSilent},
        Fault{"base_estop", [](sim::SimWorld& w, bool on) { w.base().set_estop(on); },
              core::Reason::kBaseEstop},
        Fault{"rc_takeover", [](sim::SimWorld& w, bool on) { w.base().set_rc_takeover(on); },
              core::Reason::kRcOverride},
        Fault{"base_fault", [](sim::SimWorld& w, bool) { w.base().inject_motor_fault(1); },
              core::Reason::kBaseFault}),
    [](const testing::TestParamInfo<Fault>& i) { return std::string(i.param.name); });

TEST(ClosedLoop, ShutdownCommandsZeroAndTheBaseConfirmsStandstill) {
  auto o = scenario("open");
  o.duration_s = 9.5;
  bool complete = false;
  double complete_at = -1;
  o.script = [&](double t, sim::SimWorld& w, firmware::Daemon& d) {
    if (std::abs(t - 7.0) < 1e-9) {
      EXPECT_GT(speed(w), 0.3) << "moving when SIGTERM arrives";
      d.request_shutdown();
    }
    if (t > 7.0 && !complete && d.shutdown_complete()) {
      complete = true;
      complete_at = t;
      EXPECT_EQ(speed(w), 0.0) << "standing when the daemon may exit";
    }
  };
  o.capture_can = true;
  const auto r = sim::run_simulation(o);
  ASSERT_TRUE(complete);
  EXPECT_LE(complete_at - 7.0,
            static_cast<double>(defaults().supervisor.stop_max_time_ms) / 1000.0 + 0.2);
  // The last motion command on the bus is zero.
  for (auto it = r.can_out.rbegin(); it != r.can_out.rend(); ++it) {
    if (it->id == scout_mini::id::kMotionCommand) {
      EXPECT_TRUE(
          std::all_of(it->data.begin(), it->data.begin() + 6, [](uint8_t b) { return b == 0; }));
      break;
    }
  }
}

TEST(ClosedLoop, SameSeedSameCanOutputBitForBit) {
  auto o = scenario("crossing");
  o.duration_s = 12.0;
  o.capture_can = true;
  const auto a = sim::run_simulation(o);
  const auto b = sim::run_simulation(o);
  ASSERT_GT(a.can_out.size(), 1000U);
  ASSERT_EQ(a.can_out.size(), b.can_out.size());
  for (size_t i = 0; i < a.can_out.size(); ++i) {
    ASSERT_EQ(a.can_out[i].id, b.can_out[i].id) << i;
    ASSERT_EQ(a.can_out[i].data, b.can_out[i].data) << "frame " << i;
  }
}

// ---- recorded pedestrians (scenario 11) ---------------------------------------------------------

TEST(ClosedLoop, FollowsARecordedPersonThroughARecordedCrowd) {
  const auto loaded =
      sim::load_pedestrian_dataset(std::string(COMPANION_PEDESTRIANS) + "/crowds_zara01.txt", 0.4);
  ASSERT_TRUE(loaded.ok) << loaded.error;
  std::string error;
  const auto s = sim::recorded_scenario(loaded.data, sim::longest_walk(loaded.data), &error);
  ASSERT_TRUE(s) << error;
  SimRunOptions o;
  o.config = defaults();
  o.scenario = *s;
  o.duration_s = 20.0;
  const auto r = sim::run_simulation(o);
  print(s->name, r);
  EXPECT_GT(r.metrics.tracking_s, 10.0);
  EXPECT_LT(r.metrics.longest_far_s, 5.0) << "never lost";
  EXPECT_LT(r.metrics.mean_person_distance_m, 1.6);
  EXPECT_FALSE(r.metrics.collision) << r.metrics.failure;
}

TEST(ClosedLoop, ARobotThatFellBehindCatchesUpWithThePerson) {
  // The robot starts 4 m behind a person walking away at 1 m/s: within supervisor.
  // person_max_distance_m (5 m) it drives to catch up. (At the former 3 m it held, the person
  // walked on and was never reached: in the random benchmark a lag of a second became 'lost'.)
  auto o = scenario("open");
  o.scenario.person = sim::walk({{{0, 0}}, {{30, 0}, 1.0}}, 2.0);
  o.scenario.robot_start = core::Pose2{-4.0, 0.0, 0.0};
  o.duration_s = 16.0;
  double caught_up_at = -1;
  o.script = [&](double t, sim::SimWorld& w, firmware::Daemon&) {
    const core::Pose2 r = w.robot_pose();
    const core::Pose2 p = w.person_pose();
    if (caught_up_at < 0 && std::hypot(p.x_m - r.x_m, p.y_m - r.y_m) < 1.5) caught_up_at = t;
  };
  const auto r = sim::run_simulation(o);
  print("catch up", r);
  EXPECT_GT(caught_up_at, 0) << "never within 1.5 m of the person";
  EXPECT_GT(r.metrics.active_s, 12.0) << "held instead of following";
  EXPECT_FALSE(r.metrics.collision) << r.metrics.failure;
}

// The person is measured in base_link at 120 Hz and placed in odom where the robot was then;
// the odometry comes at 50 Hz, so most frames are newer than it. Held, the newest odometry put a
// person followed at 1 m/s up to 4 cm behind where they were (2.6 cm on average here), and the
// robot that many centimetres behind q^d; carried on at the base's velocity, within 1 cm.
TEST(ClosedLoop, TheDaemonsPersonIsWhereTheyAreWhileTheRobotDrives) {
  auto o = scenario("open");
  o.scenario.person = sim::walk({{{0, 0}}, {{30, 0}, 1.0}}, 2.0);
  o.duration_s = 14.0;
  double along = 0;
  int n = 0;
  o.script = [&](double t, sim::SimWorld& w, firmware::Daemon& d) {
    if (t < 8.0) return;  // walking, followed, for 6 s
    const auto track = d.human_track().read();
    const auto base = d.base_health().read();
    if (!track || !track->value.valid || !base) return;
    const core::Nanos now(static_cast<int64_t>(std::llround(t * 1e9)));
    const firmware::BaseHealth& b = base->value;
    const core::Pose2 robot = core::carried(b.odom, {b.vx_mps, b.vy_mps, b.wz_radps},
                                            core::to_seconds(now - b.odom_stamp));
    const core::Point2 seen = robot.inverse().apply(core::position_at(track->value, now));
    const core::Point2 truth =
        w.robot_pose().inverse().apply({w.person_pose().x_m, w.person_pose().y_m});
    along += seen.x_m - truth.x_m;
    ++n;
  };
  const auto r = sim::run_simulation(o);
  print("person estimate", r);
  ASSERT_GT(n, 1000);
  std::printf("the daemon's person ahead of the true one by %.4f m on average\n", along / n);
  EXPECT_LT(std::abs(along / n), 0.01);
  EXPECT_TRUE(r.metrics.success) << r.metrics.failure;
}

// The open world with the person walking a 6 m square at 1.2 m/s, cornering left at 1 rad/s.
SimRunOptions cornering_square() {
  auto o = scenario("open");
  sim::CornerLimits corner;
  corner.turn_rate_radps = 1.0;
  o.scenario.person = sim::walk(
      {{{0, 0}}, {{6, 0}, 1.2}, {{6, 6}, 1.2}, {{0, 6}, 1.2}, {{0, 0}, 1.2}}, 2.0, 0.05, corner);
  return o;
}

TEST(ClosedLoop, WithTheGyroTheDaemonKnowsThePersonsTurnRateSooner) {
  // Round a square at 1.2 m/s, cornering at 1 rad/s. The worn sensor's gyro reaches the daemon
  // in its 0x1A frames over the serial link; with human.use_gyro the filter's turn rate follows
  // the corners where from the headings alone it lags them by ~0.1 s.
  auto run = [](bool use_gyro) {
    auto o = cornering_square();
    o.config.human.use_gyro = use_gyro;
    o.duration_s = 12.5;  // two corners
    double se = 0;
    int n = 0;
    o.script = [&](double t, sim::SimWorld& w, firmware::Daemon& d) {
      if (t < 3.0) return;
      const auto track = d.human_track().read();
      if (!track || !track->value.valid) return;
      const double err = track->value.mean_data[5] - w.scenario().person.turn_rate_at(t);
      se += err * err;
      ++n;
    };
    const auto r = sim::run_simulation(o);
    print(use_gyro ? "with the gyro" : "headings only", r);
    EXPECT_GT(n, 1500);
    return std::sqrt(se / std::max(n, 1));
  };
  const double without = run(false);
  const double with = run(true);
  std::printf("turn rate RMS error: headings only %.3f rad/s, with the gyro %.3f rad/s\n", without,
              with);
  EXPECT_LT(with, 0.5 * without);
}

TEST(ClosedLoop, QdsHeadingOnItsOwnStopsTheRobotTurningPastThePersonAfterACorner) {
  // Round a square at 1.2 m/s, cornering left at 1 rad/s. q^d's heading is predicted to keep
  // turning at the filter's rate faded over 2 s (the position's time constant): at each corner's
  // end the robot is turning fast and swings past the person's new heading. With
  // human.prediction_heading_turn_time_constant_s the heading alone fades in 0.3 s and the robot
  // stops turning near the person's heading (docs/eval/SESSIONS.md, forty-first session).
  auto run = [](double heading_turn_s) {
    auto o = cornering_square();
    o.config.human.prediction_heading_turn_time_constant_s = heading_turn_s;
    o.duration_s = 12.5;       // two corners
    double overshoot_rad = 0;  // the robot's heading past the person's (left turns: robot > person)
    o.script = [&](double t, sim::SimWorld& w, firmware::Daemon&) {
      if (t < 3.0) return;
      const double past = core::wrap_angle(w.robot_pose().theta_rad - w.person_pose().theta_rad);
      overshoot_rad = std::max(overshoot_rad, past);
    };
    const auto r = sim::run_simulation(o);
    print(heading_turn_s > 0 ? "q^d's heading on its own" : "q^d's heading with its place", r);
    EXPECT_TRUE(r.metrics.success) << r.metrics.failure;
    return overshoot_rad;
  };
  const double with_place = run(0.0);
  const double on_its_own = run(0.3);
  std::printf("largest swing past the person's heading: %.3f rad with the place, %.3f on its own\n",
              with_place, on_its_own);
  // Measured: 0.18 rad with the place, 0.12 on its own (the rest is the filter's own lag at the
  // corner's end); the same run either way without the option.
  EXPECT_LT(on_its_own, 0.8 * with_place);
}

TEST(ClosedLoop, AFadedQdPredictionStaysOnTheCostmapAndTracksABriskWalkerCloser) {
  // A person walking straight at 1.5 m/s. Carried along at constant velocity, q^d would be
  // ~15 m ahead at the end of the 10 s horizon, off the 12 m costmap (lethal there): every
  // rollout that follows it dies, the best plans are those that hold back, and the robot lags.
  // With the faded prediction (human.prediction_time_constant_s = 2 s, the default since the
  // closing-speed limit made tracking this closely safe; docs/EVALUATION.md) q^d stays on the
  // map.
  auto run = [](double time_constant_s, double& mean_plan_tracking_cost) {
    auto o = scenario("open");
    o.scenario.person = sim::walk({{{0, 0}}, {{24, 0}, 1.5}}, 2.0);
    o.duration_s = 14.0;
    o.config.human.prediction_time_constant_s = time_constant_s;
    // The prediction alone: the closing-speed limit (on by default) holds a robot beside a
    // brisk walker back either way and hides the difference in the RMSE.
    o.config.closing_speed.robot_decel_mps2 = 0.0;
    double sum = 0;
    int n = 0;
    o.script = [&](double t, sim::SimWorld&, firmware::Daemon& d) {
      const auto c = d.control_status().read();
      if (t > 6.0 && c && c->value.tracking) {  // walking at full speed
        sum += c->value.best_cost.tracking;
        ++n;
      }
    };
    auto r = sim::run_simulation(o);
    mean_plan_tracking_cost = n > 0 ? sum / n : -1.0;
    return r;
  };
  double cost_faded = 0;
  double cost_constant = 0;
  const auto faded = run(2.0, cost_faded);
  const auto constant = run(0.0, cost_constant);
  print("q^d faded", faded);
  print("q^d constant velocity", constant);
  std::printf("mean best-plan tracking cost: faded %.0f, constant velocity %.0f\n", cost_faded,
              cost_constant);
  EXPECT_TRUE(faded.metrics.success) << faded.metrics.failure;
  EXPECT_GT(cost_faded, 0.0);
  EXPECT_LT(cost_faded, 0.5 * cost_constant) << "the best plan reaches q^d's path";
  // Measured: the lag along the walk is the base's (1.5 m/s at its limit) either way; across it
  // the held-back plans also drift off q^d's line (RMSE e_y 0.05 m faded, 0.21 m constant).
  EXPECT_LT(faded.metrics.rmse_ey_m, 0.5 * constant.metrics.rmse_ey_m) << "on q^d's line";
  EXPECT_LE(faded.metrics.rmse_ex_m, constant.metrics.rmse_ex_m + 0.02) << "no more lag";
}

// A safety limit's test: the same trial with the limit off and on (`make(on)` builds it), and
// how often the limit acted by the end (`counter` of the control status). Off, the trial must
// fail with `off_failure` (the situation the test is about) and the limit never act; on, it
// must act and nothing be hit.
struct OffAndOn {
  sim::SimRunResult off, on;
  uint64_t acted_off = 0, acted_on = 0;
};
OffAndOn run_off_and_on(const std::function<SimRunOptions(bool)>& make,
                        uint64_t firmware::ControlStatus::*counter, const char* name,
                        sim::FailureKind off_failure) {
  OffAndOn r;
  for (const bool on : {false, true}) {
    SimRunOptions o = make(on);
    uint64_t& acted = on ? r.acted_on : r.acted_off;
    o.script = [&](double, sim::SimWorld&, firmware::Daemon& d) {
      if (const auto c = d.control_status().read()) acted = c->value.*counter;
    };
    (on ? r.on : r.off) = sim::run_simulation(o);
    print(std::string(name) + (on ? " on" : " off"), on ? r.on : r.off);
  }
  EXPECT_EQ(r.off.metrics.failure_kind, off_failure)
      << "the situation this test is about: " << r.off.metrics.failure;
  EXPECT_EQ(r.acted_off, 0U);
  EXPECT_FALSE(r.on.metrics.collision) << r.on.metrics.failure;
  EXPECT_GT(r.acted_on, 0U) << "the limit acted";
  return r;
}

TEST(ClosedLoop, TheClosingSpeedLimitKeepsACatchingUpRobotOffATurningPerson) {
  // Random benchmark seed 25 with q^d on the faded prediction (tight tracking): the robot,
  // catching up from behind-right at ~1.75 m/s with q^d 0.7 m to the person's right, meets
  // their 65-degree right turn at 7.3 s and, braking at the base's 1.5 m/s^2, drives into their
  // side at 7.9 s (docs/EVALUATION.md). closing_speed.* keeps its speed toward them within what
  // it can stop from in the gap between the bodies. (The whole 60 s trial still touches them
  // at 11.5 s, where they cut across its path within its braking distance: not this test's.)
  auto make = [](bool on) {
    SimRunOptions o;
    o.config = defaults();
    // The walk it was found with: the person starts at once (eased at 3 m/s^2, as the built-in
    // walks are now, they reach the turn up to 0.25 s later and the robot misses them without the
    // limit too).
    sim::RandomScenarioOptions walk_found_with;
    walk_found_with.start_stop_accel_mps2 = 0.0;
    o.scenario = sim::random_scenario(25, walk_found_with);
    o.seed = 25;
    o.duration_s = 10.0;
    o.config.human.prediction_time_constant_s = 2.0;
    // The selector weights the situation was found with (objective.alpha's default was 1 and
    // beta's 0.5; at the shipped weights the robot stays nearer its own side of the ellipse, or
    // straight behind, and does not meet this turn).
    o.config.objective.alpha = 1.0;
    o.config.objective.beta = 0.5;
    o.config.closing_speed.robot_decel_mps2 = on ? 1.0 : 0.0;
    // The controller it was found with: random samples alone (with mppi.guide_samples the robot
    // brakes out of this turn without the limit too, 0.03 m from them: no contact to prevent),
    // and the paper's heading weight (with q_theta 60 the robot turns with the person sooner and
    // misses them without the limit too).
    o.config.mppi.guide_samples = false;
    o.config.mppi.q_theta = 20.0;
    return o;
  };
  const auto r = run_off_and_on(make, &firmware::ControlStatus::closing_limits, "closing speed",
                                sim::FailureKind::kHitPerson);
  EXPECT_GT(r.on.metrics.min_person_distance_m, r.off.metrics.min_person_distance_m);
}

// mppi.path_guide through the daemon: the key reaches the controller and the status counts the
// steps with a costmap path (control.paths_planned) and those where following it became the plan
// (control.path_guided_plans); off, neither moves. Dead end, validation seed 114
// (docs/EVALUATION.md): the robot leads the person into a dead end and must get behind them as
// they walk back out; q^d's way runs past the robot where the footprint would touch the wall.
// (Whether the sample wins is the controller's cost to decide: here it is planned ~80 times in
// 31 s and is never the plan. Core: Mppi.ThePathSampleTakesTheShortWayRoundAWall.)
TEST(ClosedLoop, PathGuideIsPlannedThroughTheDaemonAndCounted) {
  auto run = [](bool path_guide, uint64_t& planned, uint64_t& guided) {
    SimRunOptions o;
    o.config = defaults();
    o.scenario = *sim::make_scenario("dead_end", 114);
    o.seed = 114;
    o.duration_s = 31.0;
    o.config.mppi.path_guide = path_guide;
    o.script = [&](double, sim::SimWorld&, firmware::Daemon& d) {
      if (const auto c = d.control_status().read()) {
        planned = c->value.paths_planned;
        guided = c->value.path_guided_plans;
      }
    };
    return sim::run_simulation(o);
  };
  uint64_t planned_off = 0, guided_off = 0, planned_on = 0, guided_on = 0;
  run(false, planned_off, guided_off);
  run(true, planned_on, guided_on);
  std::printf("control steps with a path: %llu, where it became the plan: %llu\n",
              static_cast<unsigned long long>(planned_on),
              static_cast<unsigned long long>(guided_on));
  EXPECT_EQ(planned_off, 0U);
  EXPECT_EQ(guided_off, 0U);
  EXPECT_GT(planned_on, 20U);
  EXPECT_LE(guided_on, planned_on);
}

// mppi.orbit_guide through the daemon: the fixed_side baseline in the corridor, the robot
// starting 1 m straight behind the person and q^d the point on their left. Without the orbit
// sample the robot takes the right side and stays there for the whole walk, q^d 1.5 m across
// the person (the baseline's e_y of ~1 m in docs/EVALUATION.md); with it the robot goes round
// their back to the left. The status counts the steps with q^d across the person and those
// where the orbit sample became the plan; off, neither moves. (Core:
// Mppi.TheOrbitSampleGoesRoundThePersonToTheirOtherSide.)
TEST(ClosedLoop, OrbitGuideTakesTheRobotRoundThePersonAndIsCounted) {
  struct Result {
    uint64_t planned = 0, guided = 0;
    double side_m = 0;  // the robot's lateral offset from the person at the end (+: left)
    sim::SimRunResult run;
  };
  auto run = [](bool orbit) {
    Result r;
    SimRunOptions o;
    o.config = defaults();
    o.config.policy.selector = "fixed_side";
    o.config.mppi.orbit_guide = orbit;
    o.scenario = *sim::make_scenario("corridor");
    o.duration_s = 9.0;
    o.script = [&](double, sim::SimWorld& w, firmware::Daemon& d) {
      if (const auto c = d.control_status().read()) {
        r.planned = c->value.orbits_planned;
        r.guided = c->value.orbit_guided_plans;
      }
      const core::Pose2 person = w.person_pose();
      r.side_m = person.inverse().apply(core::Point2{w.robot_pose().x_m, w.robot_pose().y_m}).y_m;
    };
    r.run = sim::run_simulation(o);
    return r;
  };
  const Result off = run(false);
  const Result on = run(true);
  std::printf(
      "robot's side of the person at 9 s: without %.2f m, with %.2f m (orbit planned %llu "
      "steps, the plan %llu); e_y %.3f against %.3f m\n",
      off.side_m, on.side_m, static_cast<unsigned long long>(on.planned),
      static_cast<unsigned long long>(on.guided), off.run.metrics.rmse_ey_m,
      on.run.metrics.rmse_ey_m);
  EXPECT_EQ(off.planned, 0U);
  EXPECT_EQ(off.guided, 0U);
  EXPECT_LT(off.side_m, -0.5) << "without: the right side, q^d across the person";
  EXPECT_GT(on.side_m, 0.5) << "with: round to q^d on the left";
  EXPECT_GT(on.planned, 0U);
  EXPECT_GT(on.guided, 0U);
  EXPECT_LE(on.guided, on.planned);
  EXPECT_FALSE(on.run.metrics.collision) << on.run.metrics.failure;
  EXPECT_LT(on.run.metrics.rmse_ey_m, off.run.metrics.rmse_ey_m);
}

// interactive_space.speed_standoff through the daemon: the static_obstacle walk (straight, 1 m/s).
// The closing-speed limit holds the robot where it can stop behind a person who stops, ~1.1 m
// back, while q^d on the ellipse is a = 1.0 m back: that gap is e_x. With the standoff, q^d
// straight behind is moved out to where the limit lets the robot keep pace (1.08 m): e_x falls
// while the robot stays as far from the person (the limit, not q^d, sets that). The standoff
// takes the person's velocity low-passed (interactive_space.speed_standoff_filter_s): unfiltered,
// the tracker's noise moves q^d by ~2 cm between samples 100 ms apart (docs/EVALUATION.md).
TEST(ClosedLoop, SpeedStandoffPutsQdWhereTheLimitHoldsTheRobot) {
  struct Result {
    double goal_behind_m = 0, robot_behind_m = 0;  // means over 6-12 s, the walk's steady part
    double goal_step_rms_m = 0;  // q^d's move from one world step (5 ms) to the next
    int samples = 0;
    sim::SimRunResult run;
  };
  auto run = [](bool standoff, double filter_s) {
    Result r;
    SimRunOptions o;
    o.config = defaults();
    o.config.interactive_space.speed_standoff = standoff;
    o.config.interactive_space.speed_standoff_filter_s = filter_s;
    o.scenario = *sim::make_scenario("static_obstacle");
    o.duration_s = 12.0;
    double previous = std::nan("");
    double step2 = 0;
    o.script = [&](double t_s, sim::SimWorld& w, firmware::Daemon& d) {
      const auto g = d.goal().read();
      if (t_s < 6.0 || !g || g->value.status != core::GoalStatus::kOk) return;
      const core::Pose2 person = w.person_pose();
      const double behind = -g->value.goal_in_person().x_m;
      r.goal_behind_m += behind;
      r.robot_behind_m -=
          person.inverse().apply(core::Point2{w.robot_pose().x_m, w.robot_pose().y_m}).x_m;
      if (!std::isnan(previous)) step2 += (behind - previous) * (behind - previous);
      previous = behind;
      ++r.samples;
    };
    r.run = sim::run_simulation(o);
    r.goal_behind_m /= std::max(r.samples, 1);
    r.robot_behind_m /= std::max(r.samples, 1);
    r.goal_step_rms_m = std::sqrt(step2 / std::max(r.samples - 1, 1));
    return r;
  };
  const double filter_s = defaults().interactive_space.speed_standoff_filter_s;
  ASSERT_GT(filter_s, 0.0);
  const Result off = run(false, filter_s);
  const Result on = run(true, filter_s);
  const Result raw = run(true, 0.0);
  std::printf(
      "q^d behind the person: without %.3f m, with %.3f m; the robot %.3f / %.3f m; e_x %.3f "
      "against %.3f m; q^d's step rms %.4f m filtered, %.4f m not\n",
      off.goal_behind_m, on.goal_behind_m, off.robot_behind_m, on.robot_behind_m,
      off.run.metrics.rmse_ex_m, on.run.metrics.rmse_ex_m, on.goal_step_rms_m, raw.goal_step_rms_m);
  ASSERT_GT(off.samples, 50);
  ASSERT_GT(on.samples, 50);
  EXPECT_NEAR(off.goal_behind_m, 1.0, 0.03) << "the ellipse's a";
  EXPECT_NEAR(on.goal_behind_m, 1.08, 0.03) << "the standoff at 1 m/s";
  EXPECT_GT(off.robot_behind_m, off.goal_behind_m + 0.04) << "the limit's gap behind q^d";
  EXPECT_NEAR(on.robot_behind_m, off.robot_behind_m, 0.03) << "the limit holds it either way";
  EXPECT_LT(on.run.metrics.rmse_ex_m, off.run.metrics.rmse_ex_m - 0.02);
  EXPECT_TRUE(on.run.metrics.success) << on.run.metrics.failure;
  EXPECT_LT(on.goal_step_rms_m, 0.5 * raw.goal_step_rms_m) << "the filter steadies q^d";
}

// The standoff and the path sample together (docs/eval/SESSIONS.md, nineteenth session): random
// validation world 174, where a pedestrian walks at the robot across its way to q^d at ~9.5 s.
// The costmap holds the pedestrian where they were seen, so each step the plan's best move is
// away from them: with q^d at the standoff (no pull against the limit) the robot backs away with
// the pedestrian until the person is 5 m off and the supervisor holds it (lost). The path round
// what the footprint would touch on the way to q^d takes it round the pedestrian instead.
TEST(ClosedLoop, WithTheStandoffThePathSampleTakesTheRobotRoundAPedestrianWalkingAtIt) {
  auto run = [](bool path_guide) {
    SimRunOptions o;
    o.config = defaults();
    o.config.interactive_space.speed_standoff = true;
    o.config.mppi.path_guide = path_guide;
    o.scenario = *sim::make_scenario("random", 174);
    o.seed = 174;
    o.duration_s = 13.0;
    return sim::run_simulation(o);
  };
  const sim::SimRunResult off = run(false);
  const sim::SimRunResult on = run(true);
  print("without the path sample", off);
  print("with it", on);
  // The metric's farthest is while the supervisor lets the robot move (not after the hold).
  EXPECT_GT(off.metrics.max_person_distance_m, 4.0) << "without: backed away with the pedestrian";
  EXPECT_LT(on.metrics.max_person_distance_m, 2.0) << "with: round them";
  EXPECT_GT(on.controller.path_guided_plans, 0U);
  EXPECT_FALSE(on.metrics.collision) << on.metrics.failure;
}

TEST(ClosedLoop, GuideSamplesBrakeAndTurnWhereRandomSamplesSwingWide) {
  // Constrained world clutter-1, seed 6 (docs/EVALUATION.md): the robot follows 1.2 m behind the
  // person at ~1.7 m/s when they turn 85 degrees left at 12.3 s. With the M random samples alone
  // the best plan keeps the robot's speed and loops wide on the cheap axis of Q (across the
  // person's new heading): 4 m out by 14.5 s, into the obstacles beside the corner, lost. The
  // structured samples (mppi.guide_samples: a brake, a law that steers to q^d's path) find the
  // brake-and-turn.
  auto run = [](bool guide_samples, uint64_t& guided_plans) {
    SimRunOptions o;
    o.config = defaults();
    sim::RandomScenarioOptions clutter;
    clutter.beside_walk_clearance_m = 1.0;
    o.scenario = sim::random_scenario(6, clutter);
    o.seed = 6;
    o.duration_s = 16.0;
    o.config.mppi.guide_samples = guide_samples;
    o.script = [&](double, sim::SimWorld&, firmware::Daemon& d) {
      if (const auto c = d.control_status().read()) guided_plans = c->value.guided_plans;
    };
    return sim::run_simulation(o);
  };
  uint64_t guided_plans_off = 0;
  uint64_t guided_plans_on = 0;
  const auto random_only = run(false, guided_plans_off);
  const auto guided = run(true, guided_plans_on);
  std::printf("plans a structured sample made: %llu of ~1500 control steps\n",
              static_cast<unsigned long long>(guided_plans_on));
  EXPECT_EQ(guided_plans_off, 0U);
  EXPECT_GT(guided_plans_on, 0U) << "counted in the status (control.guided_plans)";
  print("random samples only", random_only);
  print("with guide samples", guided);
  ASSERT_GT(random_only.metrics.max_person_distance_m, 3.0)
      << "the situation this test is about: the wide loop";
  EXPECT_FALSE(guided.metrics.collision) << guided.metrics.failure;
  EXPECT_LT(guided.metrics.max_person_distance_m, 2.5);
  // Measured: RMSE e_y 0.24 against 0.97 m (the loop is across the person's new heading).
  EXPECT_LT(guided.metrics.rmse_ey_m, 0.5 * random_only.metrics.rmse_ey_m);
}

TEST(ClosedLoop, ShutdownIsNotFooledByACommandStillInTheBasesPipeline) {
  // SIGTERM 5 ms after the robot may move: the first motion command is still inside the base's
  // 20 ms reaction, its feedback may still read zero. Complete must wait until feedback can show
  // them, so the base stands still from then on.
  auto o = scenario("open");
  o.scenario.robot_start = core::Pose2{-2.2, 0.0, 0.0};  // far from q^d: it drives off at once
  o.duration_s = 4.0;
  double active_at = -1;
  double complete_at = -1;
  bool moved_after_complete = false;
  o.script = [&](double t, sim::SimWorld& w, firmware::Daemon& d) {
    if (active_at < 0 && is_active(d)) active_at = t;
    if (active_at > 0 && std::abs(t - (active_at + 0.005)) < 1e-9) d.request_shutdown();
    if (complete_at < 0 && d.shutdown_complete()) complete_at = t;
    if (complete_at > 0 && speed(w) != 0.0) moved_after_complete = true;
  };
  sim::run_simulation(o);
  ASSERT_GT(active_at, 0);
  ASSERT_GT(complete_at, 0);
  EXPECT_FALSE(moved_after_complete) << "complete at " << complete_at;
}

// ---- leading: the dead end -------------------------------------------------------------------

// The person walks into a corridor with a closed end, turns round and walks out: behind them is
// where the robot cannot get without passing them, so it leads them out. Dead-end seed 5 (2.2 m
// wide): before a q^d ahead of the person rode the barrier's (constant-velocity) person, q^d's
// faded prediction told the robot to wait in front of the walking person, who came within the
// ellipse; the robot dodged into the wall (docs/EVALUATION.md, "Dead ends").
TEST(ClosedLoop, LeadsThePersonOutOfADeadEnd) {
  SimRunOptions o;
  o.config = defaults();
  o.scenario = *sim::make_scenario("dead_end", 5);
  const double mouth_x = o.scenario.world.segments[0].a.x_m;
  int walking_out = 0, ahead = 0;
  o.script = [&](double, sim::SimWorld& w, firmware::Daemon&) {
    const core::Pose2 p = w.person_pose();
    const core::Pose2 r = w.robot_pose();
    // Walking back out (facing -x), well inside the corridor.
    if (std::cos(p.theta_rad) < -0.9 && p.x_m > mouth_x + 1.0) {
      ++walking_out;
      if (r.x_m < p.x_m) ++ahead;
    }
  };
  const auto r = sim::run_simulation(o);
  print("dead_end-5", r);
  EXPECT_TRUE(r.metrics.success) << r.metrics.failure;
  ASSERT_GT(walking_out, 100);
  EXPECT_GT(ahead, 0.9 * walking_out) << "leading, not squeezing past";
  EXPECT_LT(r.metrics.uncomfortable_s, 0.5);
}

TEST(ClosedLoop, TheObstacleSpeedLimitKeepsTheRobotOffTheDeadEndsWall) {
  // The dead end, seed 2, with q^d held behind the person (the fixed_behind baseline, as
  // companion-eval runs it): they turn back at the end and walk at the robot, which sidesteps to
  // get behind them and, its plan squeezed between their ellipse and the wall, drives its corner
  // into the wall at 17.4 s (docs/eval/SESSIONS.md, thirty-third session). obstacle_speed.* keeps
  // every command within what stops short of the wall.
  auto make = [](bool on) {
    SimRunOptions o;
    o.config = defaults();
    o.config.policy.selector = "fixed_behind";
    o.config.mppi.threads = 1;  // as companion-eval's trials
    o.config.obstacle_speed.robot_decel_mps2 = on ? 1.0 : 0.0;
    o.scenario = *sim::make_scenario("dead_end", 2);
    o.seed = 2;
    o.duration_s = 19.0;
    return o;
  };
  const auto r = run_off_and_on(make, &firmware::ControlStatus::obstacle_limits, "obstacle speed",
                                sim::FailureKind::kHitObstacle);
  EXPECT_GT(r.on.metrics.min_static_clearance_m, 0.02);
}

// ---- the evaluation's baselines, as configuration -------------------------------------------

TEST(ClosedLoop, FixedPointBaselinesHoldTheirPointOfTheInteractiveSpace) {
  for (const char* selector : {"fixed_behind", "fixed_side"}) {
    auto o = scenario("open");
    o.config.policy.selector = selector;
    o.duration_s = 8.0;
    int goals = 0, wrong = 0;
    o.script = [&](double, sim::SimWorld&, firmware::Daemon& d) {
      const auto g = d.goal().read();
      if (!g || g->value.status != core::GoalStatus::kOk) return;
      ++goals;
      const int want = std::string(selector) == "fixed_behind" ? 32 : 16;  // n = 64
      if (g->value.index != want || std::string(g->value.selector) != selector) ++wrong;
    };
    const auto r = sim::run_simulation(o);
    EXPECT_GT(goals, 500) << selector;
    EXPECT_EQ(wrong, 0) << selector;
    EXPECT_GT(r.metrics.tracking_s, 4.0) << selector;
  }
}

TEST(ClosedLoop, PidFollowerBaselineDrivesWithoutLateralMotion) {
  auto o = scenario("open");
  o.config.control.controller = "pid_follower";
  o.duration_s = 10.0;
  double max_vy = 0, max_vx = 0;
  o.script = [&](double, sim::SimWorld&, firmware::Daemon& d) {
    const auto c = d.command().read();
    if (!c) return;
    max_vy = std::max(max_vy, std::abs(c->value.vy_mps));
    max_vx = std::max(max_vx, c->value.vx_mps);
  };
  const auto r = sim::run_simulation(o);
  EXPECT_GT(max_vx, 0.5) << "it follows the walking person";
  EXPECT_EQ(max_vy, 0.0) << "a differential-drive style follower";
  EXPECT_GT(r.metrics.tracking_s, 5.0);
}
