// companion-eval's plan: case names -> world recipes, methods -> daemon configuration.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>
#include <vector>

#include "core/geometry/pose2.hpp"
#include "eval_plan.hpp"
#include "firmware/config/config_loader.hpp"

TEST(EvalPlan, GroupsExpandToTheReferenceCases) {
  std::string error;
  auto paper = eval::expand_cases("paper", 50, error);
  ASSERT_TRUE(paper);
  ASSERT_EQ(paper->size(), 7U) << "scenarios 1-7";
  EXPECT_EQ(paper->front().name, "open");
  EXPECT_EQ(paper->front().trials, 1);
  EXPECT_EQ(paper->back().name, "random");
  EXPECT_EQ(paper->back().trials, 50);
  EXPECT_EQ(paper->back().random.pedestrians, 10);

  auto crowds = eval::expand_cases("crowds", 3, error);
  ASSERT_TRUE(crowds);
  ASSERT_EQ(crowds->size(), 4U);
  EXPECT_EQ((*crowds)[2].name, "crowd-15");
  EXPECT_EQ((*crowds)[2].random.pedestrians, 15);

  auto speeds = eval::expand_cases("speeds", 3, error);
  ASSERT_TRUE(speeds);
  ASSERT_EQ(speeds->size(), 3U);
  EXPECT_EQ((*speeds)[0].random.speed_min_mps, 0.75);
  EXPECT_EQ((*speeds)[0].random.speed_max_mps, 0.75);

  auto size = eval::expand_cases("size-1.2x0.9", 3, error);
  ASSERT_TRUE(size);
  EXPECT_EQ(size->front().ellipse_a_m, 1.2);
  EXPECT_EQ(size->front().ellipse_b_m, 0.9);

  auto constrained = eval::expand_cases("constrained", 3, error);
  ASSERT_TRUE(constrained);
  ASSERT_EQ(constrained->size(), 4U);
  EXPECT_EQ((*constrained)[1].name, "clutter-1");
  EXPECT_EQ((*constrained)[1].random.beside_walk_clearance_m, 1.0);
  EXPECT_EQ((*constrained)[3].name, "dead_end");
  EXPECT_EQ((*constrained)[3].trials, 3) << "seeded dead ends, as many as random trials";
  for (const auto& c : *paper)
    EXPECT_NE(c.name, "dead_end") << "not one of the paper's 1-7";
  EXPECT_EQ(paper->back().random.beside_walk_clearance_m, 0) << "the benchmark stays as it was";
  EXPECT_EQ(paper->back().random.max_turn_rad, 1.75) << "the benchmark's turns, +-100 degrees";
  EXPECT_EQ(paper->back().random.corner_turn_rate_radps, 3.0);

  auto gentle = eval::expand_cases("turns-30x1", 3, error);
  ASSERT_TRUE(gentle);
  EXPECT_EQ(gentle->front().name, "turns-30x1");
  EXPECT_EQ(gentle->front().trials, 3);
  EXPECT_NEAR(gentle->front().random.max_turn_rad, 0.5236, 1e-4);
  EXPECT_EQ(gentle->front().random.corner_turn_rate_radps, 1.0);
  auto turns_only = eval::expand_cases("turns-45", 3, error);
  ASSERT_TRUE(turns_only);
  EXPECT_NEAR(turns_only->front().random.max_turn_rad, 0.7854, 1e-4);
  EXPECT_EQ(turns_only->front().random.corner_turn_rate_radps, 3.0) << "the benchmark's rate";

  for (const char* bad : {"moon", "crowd-x", "speed-0", "size-1.2", "size-9x9", "crowd-1000",
                          "clutter-0.2", "clutter-", "clutter-1m", "turns-", "turns-200",
                          "turns-30x0", "turns-30x", "turns-x1", "turns-30y1"}) {
    EXPECT_FALSE(eval::expand_cases(bad, 3, error)) << bad;
    EXPECT_NE(error.find("unknown case"), std::string::npos);
  }
}

TEST(EvalPlan, MethodsSetTheSelectorAndTheController) {
  const auto base = *firmware::load_default_config().config;
  std::string error;
  const auto sizes = eval::expand_cases("size-1.2x0.9", 1, error);
  const auto pid = eval::method_by_name("pid");
  ASSERT_TRUE(pid);
  const auto cfg = eval::trial_config(base, sizes->front(), *pid);
  EXPECT_EQ(cfg.control.controller, "pid_follower");
  EXPECT_EQ(cfg.devices.tracker, "sim");
  EXPECT_EQ(cfg.interactive_space.ellipse_a_m, 1.2);
  EXPECT_EQ(cfg.mppi.threads, 1) << "one trial per core";
  const auto fixed = eval::trial_config(base, sizes->front(), *eval::method_by_name("fixed_side"));
  EXPECT_EQ(fixed.policy.selector, "fixed_side");
  EXPECT_EQ(fixed.control.controller, "mppi_cbf");
  EXPECT_FALSE(eval::method_by_name("teleport"));
}

TEST(EvalPlan, RandomWorldsDifferBySeedAndRepeatForTheSameSeed) {
  std::string error;
  const auto c = eval::expand_cases("random", 2, error)->front();
  const auto a = eval::make_world(c, 1);
  const auto b = eval::make_world(c, 2);
  const auto a2 = eval::make_world(c, 1);
  EXPECT_EQ(a.name, "random-1");
  EXPECT_EQ(a.pedestrians.size(), 10U);
  EXPECT_NE(a.person.end_s(), b.person.end_s());
  EXPECT_EQ(a.person.end_s(), a2.person.end_s());
  EXPECT_EQ(a.world.segments.size(), a2.world.segments.size());
}

namespace {
// The smallest distance from the person's walk to a static obstacle, and the share of the walk
// where an obstacle is nearer than `closed_m` (the points beside the person closed).
std::pair<double, double> walk_clearance(const sim::Scenario& s, double closed_m) {
  double nearest = 1e9;
  int closed = 0;
  for (const sim::TimedPose& tp : s.person.samples()) {
    const double d = s.world.distance({tp.pose.x_m, tp.pose.y_m});
    nearest = std::min(nearest, d);
    closed += d < closed_m ? 1 : 0;
  }
  return {nearest, static_cast<double>(closed) / static_cast<double>(s.person.samples().size())};
}
}  // namespace

TEST(EvalPlan, DeadEndsAreSeededCorridorsThePersonWalksOutOfAgain) {
  std::string error;
  const auto cases = eval::expand_cases("dead_end", 4, error);
  ASSERT_TRUE(cases);
  ASSERT_EQ(cases->size(), 1U);
  const sim::Scenario a = eval::make_world(cases->front(), 3);
  const sim::Scenario again = eval::make_world(cases->front(), 3);
  const sim::Scenario b = eval::make_world(cases->front(), 4);
  EXPECT_EQ(a.name, "dead_end-3");
  ASSERT_EQ(a.world.segments.size(), 3U) << "two side walls and the end";
  EXPECT_EQ(a.world.segments[2].a.x_m, again.world.segments[2].a.x_m) << "same seed, same world";
  EXPECT_NE(a.world.segments[2].a.x_m, b.world.segments[2].a.x_m) << "another seed, another";
  // The person goes in to near the end wall, and comes back out past the corridor's mouth,
  // without touching its walls on the way (they turn round 0.6 m from the end wall; the side
  // walls are at least 1 m from them).
  const double end_x = a.world.segments[2].a.x_m;
  const double mouth_x = a.world.segments[0].a.x_m;
  double deepest = -1e9;
  bool out_again = false;
  for (const auto& tp : a.person.samples()) {
    deepest = std::max(deepest, tp.pose.x_m);
    if (deepest > end_x - 1.0 && tp.pose.x_m < mouth_x - 0.5) out_again = true;
    EXPECT_GT(a.world.distance({tp.pose.x_m, tp.pose.y_m}), a.person_radius_m + 0.3) << tp.t_s;
  }
  EXPECT_GT(deepest, end_x - 1.0);
  EXPECT_TRUE(out_again);
  // It starts with the robot 1 m behind the person, outside the corridor.
  EXPECT_LT(a.robot_start.x_m, mouth_x);
}

TEST(EvalPlan, ConstrainedWorldsAreTheSeedsWorldWithObstaclesBesideTheWalk) {
  std::string error;
  const auto open = eval::expand_cases("random", 1, error)->front();
  const auto tight = eval::expand_cases("clutter-1.0", 1, error)->front();
  double open_closed = 0, tight_closed = 0;
  for (uint32_t seed = 1; seed <= 10; ++seed) {
    const sim::Scenario a = eval::make_world(open, seed);
    const sim::Scenario b = eval::make_world(tight, seed);
    const auto [open_nearest, open_share] = walk_clearance(a, 1.45);
    const auto [tight_nearest, tight_share] = walk_clearance(b, 1.45);
    EXPECT_GE(tight_nearest, 1.0 - 1e-9) << "seed " << seed << ": boxes' corners count";
    EXPECT_LT(tight_nearest, 1.35) << "seed " << seed << ": obstacles reach the walk";
    open_closed += open_share;
    tight_closed += tight_share;
    // Beneath the new obstacles, the seed's world as it was: cases pair by seed.
    EXPECT_EQ(a.person.samples().back().pose.x_m, b.person.samples().back().pose.x_m);
    ASSERT_EQ(a.pedestrians.size(), b.pedestrians.size());
    EXPECT_EQ(a.pedestrians[3].position.x_m, b.pedestrians[3].position.x_m);
    ASSERT_GT(b.world.segments.size() + b.world.circles.size(),
              a.world.segments.size() + a.world.circles.size());
    for (size_t i = 0; i < a.world.circles.size(); ++i) {
      EXPECT_EQ(a.world.circles[i].center.x_m, b.world.circles[i].center.x_m);
    }
  }
  EXPECT_LT(open_closed / 10, 0.02) << "the benchmark's worlds hardly close the points beside";
  EXPECT_GT(tight_closed / 10, 0.25) << "a constrained world closes them on much of the walk";
}

namespace {
struct WalkTurns {
  double max_rate_radps = 0;  // the person's largest heading rate while walking
  int windows = 0;            // 2 s windows walked all through
  int windows_over_90 = 0;    // ... in which the heading turned more than 90 degrees
};
// From the walk's 50 ms samples, counting only while the person walks (faster than 0.5 m/s).
WalkTurns walk_turns(const sim::Scenario& s) {
  const auto& samples = s.person.samples();
  WalkTurns out;
  std::vector<bool> walking(samples.size(), false);
  for (size_t k = 1; k < samples.size(); ++k) {
    const auto& a = samples[k - 1];
    const auto& b = samples[k];
    const double dt = b.t_s - a.t_s;
    const double moved = std::hypot(b.pose.x_m - a.pose.x_m, b.pose.y_m - a.pose.y_m);
    if (dt <= 0 || moved / dt < 0.5) continue;
    walking[k] = true;
    const double rate = std::abs(core::wrap_angle(b.pose.theta_rad - a.pose.theta_rad)) / dt;
    out.max_rate_radps = std::max(out.max_rate_radps, rate);
  }
  constexpr size_t kWindow = 40;  // 2 s of 50 ms samples
  for (size_t k = kWindow; k < samples.size(); ++k) {
    if (!std::all_of(walking.begin() + static_cast<long>(k - kWindow) + 1,
                     walking.begin() + static_cast<long>(k) + 1, [](bool w) { return w; })) {
      continue;
    }
    ++out.windows;
    const double turned =
        core::wrap_angle(samples[k].pose.theta_rad - samples[k - kWindow].pose.theta_rad);
    if (std::abs(turned) > std::numbers::pi / 2) ++out.windows_over_90;
  }
  return out;
}
}  // namespace

TEST(EvalPlan, GentleTurnsBoundTheWalksTurnsAndKeepItInTheSquare) {
  std::string error;
  const auto sharp = eval::expand_cases("random", 1, error)->front();
  const auto gentle = eval::expand_cases("turns-30x1", 1, error)->front();
  WalkTurns a_all, b_all;
  for (uint32_t seed = 1; seed <= 20; ++seed) {
    const sim::Scenario a = eval::make_world(sharp, seed);
    const sim::Scenario b = eval::make_world(gentle, seed);
    EXPECT_EQ(b.name, fmt::format("turns-30x1-{}", seed));
    const WalkTurns at = walk_turns(a);
    const WalkTurns bt = walk_turns(b);
    EXPECT_LE(bt.max_rate_radps, 1.0 + 1e-6) << "seed " << seed << ": corners at 1 rad/s at most";
    a_all.max_rate_radps = std::max(a_all.max_rate_radps, at.max_rate_radps);
    a_all.windows += at.windows;
    a_all.windows_over_90 += at.windows_over_90;
    b_all.windows += bt.windows;
    b_all.windows_over_90 += bt.windows_over_90;
    for (const auto& tp : b.person.samples()) {
      ASSERT_LT(std::max(std::abs(tp.pose.x_m), std::abs(tp.pose.y_m)), 12.0) << seed;
    }
    // The same seed's pedestrians: only the person's walk (and what stands clear of it) differs.
    ASSERT_EQ(a.pedestrians.size(), b.pedestrians.size());
  }
  EXPECT_GT(a_all.max_rate_radps, 2.9) << "the benchmark's corners at 3 rad/s";
  const double sharp_share = 1.0 * a_all.windows_over_90 / a_all.windows;
  const double gentle_share = 1.0 * b_all.windows_over_90 / b_all.windows;
  EXPECT_GT(sharp_share, 0.05) << "the benchmark turns more than 90 degrees in 2 s often";
  // A gentle walk only where it meets the square's edge and turns round at 1 rad/s.
  EXPECT_LT(gentle_share, 0.02);
}
