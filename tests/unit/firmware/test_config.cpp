#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "firmware/config/config_loader.hpp"

using firmware::ConfigResult;
using firmware::load_config_text;

namespace {

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Exactly one error, at `line`, about `key`, whose message contains `text`.
void expect_error(const ConfigResult& r, int line, const std::string& key,
                  const std::string& text) {
  ASSERT_FALSE(r.ok());
  ASSERT_EQ(r.errors.size(), 1U) << r.errors[0].to_string();
  const auto& e = r.errors[0];
  EXPECT_EQ(e.file, "test.yaml");
  EXPECT_EQ(e.line, line) << e.to_string();
  EXPECT_EQ(e.key, key) << e.to_string();
  EXPECT_NE(e.message.find(text), std::string::npos) << e.to_string();
  // The printed form names file, line and key.
  EXPECT_NE(e.to_string().find("test.yaml:" + std::to_string(line) + ": '" + key + "'"),
            std::string::npos)
      << e.to_string();
}

}  // namespace

TEST(Config, DefaultsLoadAndMatchThePaper) {
  const auto r = firmware::load_default_config();
  ASSERT_TRUE(r.ok()) << r.errors[0].to_string();
  const auto& c = *r.config;
  EXPECT_EQ(c.interactive_space.points, 64);
  EXPECT_DOUBLE_EQ(c.interactive_space.ellipse_a_m, 1.0);
  EXPECT_DOUBLE_EQ(c.interactive_space.ellipse_b_m, 0.7);
  EXPECT_DOUBLE_EQ(c.interactive_space.cost_threshold, 30);
  EXPECT_EQ(c.mppi.horizon_steps, 100);
  EXPECT_EQ(c.mppi.samples, 2000);
  EXPECT_DOUBLE_EQ(c.mppi.step_s, 0.1);
  EXPECT_DOUBLE_EQ(c.mppi.lambda, 1.0);
  EXPECT_DOUBLE_EQ(c.mppi.q_x, 50);
  EXPECT_DOUBLE_EQ(c.mppi.q_y, 10);
  EXPECT_DOUBLE_EQ(c.mppi.q_theta, 60);  // not the paper's 20: docs/EVALUATION.md
  EXPECT_DOUBLE_EQ(c.mppi.collision_cost, 1000);
  EXPECT_DOUBLE_EQ(c.dcbf.delta, 0.5);
  EXPECT_DOUBLE_EQ(c.dcbf.c_safe, 5000);
}

TEST(Config, ShippedDefaultFileIsTheBuiltInOne) {
  EXPECT_EQ(read_file(std::string(COMPANION_SOURCE_DIR) + "/config/companiond.yaml"),
            firmware::default_config_yaml());
}

TEST(Config, ReferenceDocumentIsUpToDate) {
  // config/README.md is generated: `companiond --config-reference > config/README.md`.
  EXPECT_EQ(read_file(std::string(COMPANION_SOURCE_DIR) + "/config/README.md"),
            firmware::config_reference_markdown());
}

TEST(Config, PartialFileOverridesOnlyItsKeys) {
  const auto r = load_config_text("supervisor:\n  tracker_timeout_ms: 50\n", "test.yaml");
  ASSERT_TRUE(r.ok()) << r.errors[0].to_string();
  EXPECT_EQ(r.config->supervisor.tracker_timeout_ms, 50);
  EXPECT_EQ(r.config->supervisor.lidar_timeout_ms, 300);
}

TEST(Config, EmptyFileMeansDefaults) {
  EXPECT_TRUE(load_config_text("", "test.yaml").ok());
  EXPECT_TRUE(load_config_text("# only a comment\n", "test.yaml").ok());
}

TEST(Config, PrintedConfigLoadsBackToTheSameValues) {
  auto r = load_config_text("mppi:\n  samples: 512\ndevices:\n  base: \"slcan:/dev/ttyACM0\"\n",
                            "test.yaml");
  ASSERT_TRUE(r.ok());
  const std::string printed = firmware::print_config(*r.config);
  const auto again = load_config_text(printed, "printed.yaml");
  ASSERT_TRUE(again.ok()) << again.errors[0].to_string();
  EXPECT_EQ(firmware::print_config(*again.config), printed);
  EXPECT_NE(printed.find("samples: 512"), std::string::npos);
}

TEST(Config, UnknownKeyIsRefused) {
  expect_error(load_config_text("supervisor:\n  tracker_timeout_ms: 50\n  tracker_timout_ms: 60\n",
                                "test.yaml"),
               3, "supervisor.tracker_timout_ms", "unknown key");
}

TEST(Config, UnknownSectionIsRefused) {
  expect_error(load_config_text("supervisr:\n  x: 1\n", "test.yaml"), 1, "supervisr",
               "unknown key");
}

TEST(Config, DuplicateKeyIsRefused) {
  expect_error(load_config_text("mppi:\n  samples: 100\n  samples: 200\n", "test.yaml"), 3,
               "mppi.samples", "duplicate");
}

TEST(Config, WrongTypesAreRefused) {
  expect_error(load_config_text("mppi:\n  lambda: fast\n", "test.yaml"), 2, "mppi.lambda",
               "expected a finite number");
  expect_error(load_config_text("mppi:\n  samples: 2000.5\n", "test.yaml"), 2, "mppi.samples",
               "expected an integer");
  expect_error(load_config_text("realtime:\n  require: maybe\n", "test.yaml"), 2,
               "realtime.require", "expected true or false");
  expect_error(load_config_text("mppi:\n  lambda: .nan\n", "test.yaml"), 2, "mppi.lambda",
               "finite");
  expect_error(load_config_text("mppi:\n  samples: [1, 2]\n", "test.yaml"), 2, "mppi.samples",
               "list");
  expect_error(load_config_text("mppi: 3\n", "test.yaml"), 1, "mppi", "mapping");
}

TEST(Config, OutOfRangeValuesAreRefused) {
  expect_error(load_config_text("dcbf:\n  delta: 1.5\n", "test.yaml"), 2, "dcbf.delta",
               "out of range");
  expect_error(load_config_text("limits:\n  vx_max_mps: 3.5\n", "test.yaml"), 2,
               "limits.vx_max_mps", "out of range [0, 3]");
  expect_error(load_config_text("mppi:\n  samples: 0\n", "test.yaml"), 2, "mppi.samples",
               "out of range");
  // A zero noise sigma would divide the control cost by zero: every MPPI step would fail.
  expect_error(load_config_text("mppi:\n  noise_vx_mps: 0\n", "test.yaml"), 2, "mppi.noise_vx_mps",
               "out of range");
}

TEST(Config, TheBaselinesAreChoices) {
  expect_error(load_config_text("policy:\n  selector: random\n", "test.yaml"), 2, "policy.selector",
               "not one of");
  expect_error(load_config_text("control:\n  controller: dwa\n", "test.yaml"), 2,
               "control.controller", "not one of");
  const auto ok = load_config_text(
      "policy:\n  selector: fixed_side\ncontrol:\n  controller: "
      "pid_follower\n",
      "test.yaml");
  ASSERT_TRUE(ok.ok());
  EXPECT_EQ(ok.config->policy.selector, "fixed_side");
  EXPECT_EQ(ok.config->control.controller, "pid_follower");
}

TEST(Config, BadChoicesAreRefused) {
  expect_error(load_config_text("devices:\n  base: \"can0\"\n", "test.yaml"), 2, "devices.base",
               "socketcan:...");
  expect_error(load_config_text("logging:\n  level: loud\n", "test.yaml"), 2, "logging.level",
               "not one of");
  expect_error(load_config_text("devices:\n  lidar: \"udp:\"\n", "test.yaml"), 2, "devices.lidar",
               "not one of");
}

TEST(Config, SyntaxErrorNamesTheLine) {
  const auto r = load_config_text("mppi:\n  samples: 10\n   lambda: [1\n", "test.yaml");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.errors[0].file, "test.yaml");
  EXPECT_GE(r.errors[0].line, 2);
  EXPECT_NE(r.errors[0].message.find("YAML syntax error"), std::string::npos);
}

TEST(Config, MissingFileIsRefused) {
  const auto r = firmware::load_config_file("/nonexistent/companiond.yaml");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.errors[0].file, "/nonexistent/companiond.yaml");
  EXPECT_NE(r.errors[0].message.find("cannot open"), std::string::npos);
}

TEST(Config, AllErrorsOfAFileAreReportedAtOnce) {
  const auto r =
      load_config_text("mppi:\n  samples: -1\n  lamda: 1\ndcbf:\n  delta: x\n", "test.yaml");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.errors.size(), 3U);
}

TEST(Config, RelationsBetweenKeysAreChecked) {
  expect_error(load_config_text("tracker:\n  quality_bad_below: 150\n  quality_good_min: 120\n",
                                "test.yaml"),
               3, "tracker.quality_good_min", "must be >= tracker.quality_bad_below (150)");
  // The offending key may come from the defaults: then there is no line.
  const auto r = load_config_text("tracker:\n  reconnect_first_ms: 9000\n", "test.yaml");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.errors[0].key, "tracker.reconnect_max_ms");
  EXPECT_EQ(r.errors[0].line, 0);
  EXPECT_TRUE(
      load_config_text("tracker:\n  quality_bad_below: 120\n  quality_good_min: 120\n", "test.yaml")
          .ok());
  expect_error(load_config_text("mppi:\n  guide_samples: false\n  path_guide: true\n", "test.yaml"),
               3, "mppi.path_guide", "needs mppi.guide_samples: true");
  EXPECT_TRUE(load_config_text("mppi:\n  path_guide: true\n", "test.yaml").ok());
  expect_error(
      load_config_text("mppi:\n  guide_samples: false\n  path_guide: false\n  orbit_guide: true\n",
                       "test.yaml"),
      4, "mppi.orbit_guide", "needs mppi.guide_samples: true");
  EXPECT_TRUE(load_config_text("mppi:\n  orbit_guide: true\n", "test.yaml").ok());
  expect_error(load_config_text("closing_speed:\n  robot_decel_mps2: 0\ninteractive_space:\n"
                                "  speed_standoff: true\n",
                                "test.yaml"),
               4, "interactive_space.speed_standoff", "needs closing_speed.robot_decel_mps2 > 0");
  EXPECT_TRUE(load_config_text("interactive_space:\n  speed_standoff: true\n", "test.yaml").ok());
}

TEST(Config, TrackerDeviceUriIsChecked) {
  expect_error(load_config_text("devices:\n  tracker: \"serial:/dev/ttyUSB0@fast\"\n", "test.yaml"),
               2, "devices.tracker", "baud rate 'fast'");
  EXPECT_TRUE(
      load_config_text("devices:\n  tracker: \"serial:/dev/ttyUSB0@921600\"\n", "test.yaml").ok());
}

TEST(Config, LidarEndpointAndCostmapBandAreChecked) {
  expect_error(load_config_text("devices:\n  lidar: \"udp:0.0.0.0:99999\"\n", "test.yaml"), 2,
               "devices.lidar", "port '99999'");
  expect_error(load_config_text("costmap:\n  resolution_m: 0.02\n  z_max_m: 2.0\n", "test.yaml"), 3,
               "costmap.z_max_m", "at most 64 voxels");
}

#include "firmware/daemon.hpp"

TEST(Config, ControllerParametersComeFromTheConfigurationAsInThePaper) {
  const auto c = firmware::mppi_config(*firmware::load_default_config().config);
  EXPECT_EQ(c.horizon_steps, 100);
  EXPECT_DOUBLE_EQ(c.step_s, 0.1);
  EXPECT_EQ(c.samples, 2000);
  EXPECT_DOUBLE_EQ(c.lambda, 1.0);
  // The paper's Q but the heading weight (60: docs/eval/SESSIONS.md, twenty-third session).
  EXPECT_EQ(c.q, (std::array<double, 3>{50.0, 10.0, 60.0}));
  EXPECT_EQ(c.tracking_frame, core::TrackingFrame::kGoal);
  EXPECT_DOUBLE_EQ(c.collision_cost, 1000.0);
  EXPECT_DOUBLE_EQ(c.cost_threshold, 30.0);
  EXPECT_DOUBLE_EQ(c.dcbf_delta, 0.5);
  EXPECT_DOUBLE_EQ(c.c_safe, 5000.0);
  EXPECT_DOUBLE_EQ(c.ellipse.a_m, 1.0);
  EXPECT_DOUBLE_EQ(c.ellipse.b_m, 0.7);
  EXPECT_DOUBLE_EQ(c.limits.vx, 1.8);
  const auto w = firmware::interactive_space_config(*firmware::load_default_config().config);
  EXPECT_EQ(w.points, 64);
  EXPECT_DOUBLE_EQ(w.cost_threshold, 30.0);
  EXPECT_TRUE(w.speed_standoff)
      << "with mppi.path_guide (docs/eval/SESSIONS.md, nineteenth session)";
  EXPECT_TRUE(c.path_guide);
  EXPECT_DOUBLE_EQ(w.closing.robot_decel_mps2, c.closing.robot_decel_mps2) << "the limit's own";
  EXPECT_DOUBLE_EQ(w.closing.footprint.x_max_m, c.closing.footprint.x_max_m);
  // The shipped weights of G are the core defaults, whose behaviour test_interactive_space pins
  // (InteractiveSpace.DefaultWeightsSendALaggingRobotBehindThePersonNotBesideThem): changing
  // either alone fails here.
  const core::InteractiveSpaceConfig core_defaults;
  EXPECT_DOUBLE_EQ(w.alpha, core_defaults.alpha);
  EXPECT_DOUBLE_EQ(w.beta, core_defaults.beta);
  EXPECT_DOUBLE_EQ(w.gamma, core_defaults.gamma);
  EXPECT_DOUBLE_EQ(w.delta, core_defaults.delta);
  EXPECT_DOUBLE_EQ(w.switch_cost, core_defaults.switch_cost);
  EXPECT_DOUBLE_EQ(w.a_m, core_defaults.a_m);
  EXPECT_DOUBLE_EQ(w.b_m, core_defaults.b_m);
}

// The contact tier: its cost from the file, its threshold the costmap's cost at the footprint's
// circumscribed radius (0.35 x 0.30 m half-extents: 0.461 m, cost 99 exp(-3 (0.461 - 0.35))).
TEST(Config, TheContactTierIsWhereTheFootprintCanTouch) {
  const auto c = firmware::mppi_config(*firmware::load_default_config().config);
  EXPECT_DOUBLE_EQ(c.contact_cost, 100000.0);
  EXPECT_NEAR(c.contact_threshold, 99.0 * std::exp(-3.0 * (std::hypot(0.35, 0.30) - 0.35)), 1e-9);
  EXPECT_GT(c.contact_threshold, c.cost_threshold);
  const auto wide = load_config_text(
      "costmap:\n  footprint_y_min_m: -0.45\n  footprint_y_max_m: 0.45\nmppi:\n  contact_cost: 0\n",
      "test.yaml");
  ASSERT_TRUE(wide.ok()) << wide.errors[0].to_string();
  const auto w = firmware::mppi_config(*wide.config);
  EXPECT_DOUBLE_EQ(w.contact_cost, 0.0);
  EXPECT_LT(w.contact_threshold, c.contact_threshold) << "a wider robot touches from farther";
}

TEST(Config, ThePredictedTurnRateTimeConstantReachesTheFilterConfig) {
  const auto d = firmware::human_ekf_config(*firmware::load_default_config().config);
  EXPECT_DOUBLE_EQ(d.prediction_turn_time_constant_s, 0.0) << "the default: as the velocity";
  const auto set =
      load_config_text("human:\n  prediction_turn_time_constant_s: 0.5\n", "test.yaml");
  ASSERT_TRUE(set.ok()) << set.errors[0].to_string();
  EXPECT_DOUBLE_EQ(firmware::human_ekf_config(*set.config).prediction_turn_time_constant_s, 0.5);
  EXPECT_FALSE(
      load_config_text("human:\n  prediction_turn_time_constant_s: -1\n", "test.yaml").ok());
  EXPECT_DOUBLE_EQ(d.prediction_heading_turn_time_constant_s, 0.0) << "the default: as q^d";
  const auto heading =
      load_config_text("human:\n  prediction_heading_turn_time_constant_s: 0.4\n", "test.yaml");
  ASSERT_TRUE(heading.ok()) << heading.errors[0].to_string();
  EXPECT_DOUBLE_EQ(
      firmware::human_ekf_config(*heading.config).prediction_heading_turn_time_constant_s, 0.4);
  EXPECT_FALSE(
      load_config_text("human:\n  prediction_heading_turn_time_constant_s: nan\n", "test.yaml")
          .ok());
}

TEST(Config, TheTrackingFrameIsAChoiceThatReachesTheController) {
  expect_error(load_config_text("mppi:\n  tracking_frame: odom\n", "test.yaml"), 2,
               "mppi.tracking_frame", "not one of");
  const auto r = load_config_text("mppi:\n  tracking_frame: robot\n", "test.yaml");
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(firmware::mppi_config(*r.config).tracking_frame, core::TrackingFrame::kRobot);
}

TEST(Config, TheSteeringLawsHeadingGainReachesTheControllerAndIsBounded) {
  EXPECT_DOUBLE_EQ(
      firmware::mppi_config(*firmware::load_default_config().config).guide_heading_gain_per_s, 2.0);
  const auto r = load_config_text("mppi:\n  guide_heading_gain_per_s: 6\n", "test.yaml");
  ASSERT_TRUE(r.ok()) << r.errors[0].to_string();
  EXPECT_DOUBLE_EQ(firmware::mppi_config(*r.config).guide_heading_gain_per_s, 6.0);
  expect_error(load_config_text("mppi:\n  guide_heading_gain_per_s: 0\n", "test.yaml"), 2,
               "mppi.guide_heading_gain_per_s", "out of range [0.5, 20]");
}

TEST(Config, ThePlansReverseLimitReachesTheControllerAndIsBounded) {
  EXPECT_DOUBLE_EQ(
      firmware::mppi_config(*firmware::load_default_config().config).reverse_speed_max_mps, 1.8)
      << "the default: as fast as forward (limits.vx_max_mps)";
  const auto r = load_config_text("mppi:\n  reverse_speed_max_mps: 0.6\n", "test.yaml");
  ASSERT_TRUE(r.ok()) << r.errors[0].to_string();
  EXPECT_DOUBLE_EQ(firmware::mppi_config(*r.config).reverse_speed_max_mps, 0.6);
  expect_error(load_config_text("mppi:\n  reverse_speed_max_mps: -0.1\n", "test.yaml"), 2,
               "mppi.reverse_speed_max_mps", "out of range [0, 3]");
  expect_error(load_config_text("mppi:\n  reverse_speed_max_mps: 3.5\n", "test.yaml"), 2,
               "mppi.reverse_speed_max_mps", "out of range [0, 3]");
}

TEST(Config, TheSwitchCostReachesTheSelectorAndMustNotBeNegative) {
  const auto r = load_config_text("objective:\n  switch_cost: 0.05\n", "test.yaml");
  ASSERT_TRUE(r.ok());
  EXPECT_DOUBLE_EQ(firmware::interactive_space_config(*r.config).switch_cost, 0.05);
  expect_error(load_config_text("objective:\n  switch_cost: -0.1\n", "test.yaml"), 2,
               "objective.switch_cost", "out of range [0, 1000]");
}

TEST(Config, ANegativeAlphaIsAcceptedAndReachesTheSelector) {
  // alpha < 0 makes G prefer the ellipse's far points (along the person's heading): an
  // evaluated setting (docs/EVALUATION.md), so the schema must let it through, within bounds.
  const auto r = load_config_text("objective:\n  alpha: -16.0\n", "test.yaml");
  ASSERT_TRUE(r.ok());
  EXPECT_DOUBLE_EQ(firmware::interactive_space_config(*r.config).alpha, -16.0);
  expect_error(load_config_text("objective:\n  alpha: -1001.0\n", "test.yaml"), 2,
               "objective.alpha", "out of range [-1000, 1000]");
}

TEST(Config, TheControlOverrunRuleReachesTheSupervisorAndIsBounded) {
  const auto r = load_config_text(
      "supervisor:\n  control_overruns_to_hold: 5\n  control_overrun_window_ms: 2000\n",
      "test.yaml");
  ASSERT_TRUE(r.ok()) << r.errors[0].to_string();
  const core::SupervisorConfig s = firmware::supervisor_config(*r.config);
  EXPECT_EQ(s.control_overruns_to_hold, 5U);
  EXPECT_EQ(s.control_overrun_window, std::chrono::milliseconds(2000));
  const core::SupervisorConfig d =
      firmware::supervisor_config(*firmware::load_default_config().config);
  EXPECT_EQ(d.control_overruns_to_hold, 3U);
  EXPECT_EQ(d.control_overrun_window, std::chrono::milliseconds(1000));
  // 0 would hold for ever; more than the supervisor's ring holds would never hold.
  expect_error(load_config_text("supervisor:\n  control_overruns_to_hold: 0\n", "test.yaml"), 2,
               "supervisor.control_overruns_to_hold", "out of range [1, 16]");
  expect_error(load_config_text("supervisor:\n  control_overruns_to_hold: 17\n", "test.yaml"), 2,
               "supervisor.control_overruns_to_hold", "out of range [1, 16]");
}
