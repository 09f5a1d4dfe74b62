// companion-eval's plan: case names -> world recipes, methods -> daemon configuration.
#include <gtest/gtest.h>

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

  for (const char* bad : {"moon", "crowd-x", "speed-0", "size-1.2", "size-9x9", "crowd-1000"}) {
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
