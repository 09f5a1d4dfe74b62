#include <gtest/gtest.h>

#include "core/scheduler/task_stats.hpp"

using namespace std::chrono_literals;
using core::TaskStats;
using core::TaskTiming;

TEST(TaskStats, CountsOverrunsSkipsAndBudget) {
  TaskStats s(10ms, 3ms);
  s.record(TaskTiming{0ms, 0ms, 0ms, 1ms, 10ms, 0});      // fine
  s.record(TaskTiming{10ms, 10ms, 10ms, 14ms, 20ms, 0});  // over budget, not an overrun
  s.record(TaskTiming{20ms, 20ms, 20ms, 32ms, 30ms, 0});  // overrun
  s.record(TaskTiming{30ms, 40ms, 40ms, 41ms, 50ms, 1});  // one release (30 ms) skipped
  EXPECT_EQ(s.runs(), 4U);
  EXPECT_EQ(s.budget_exceeded(), 2U);
  EXPECT_EQ(s.overruns(), 1U);
  EXPECT_EQ(s.skipped(), 1U);
  EXPECT_EQ(s.last_end(), 41ms);
  EXPECT_EQ(s.run_time().max(), 12ms);
  EXPECT_EQ(s.start_latency().max(), 10ms) << "the skipping run began 10 ms after 30 ms was due";
}

TEST(TaskStats, PeriodJitterIsTheDeviationOfTheStartInterval) {
  TaskStats s(10ms, 1ms);
  s.record(TaskTiming{0ms, 0ms, 0ms, 1ms, 10ms, 0});
  s.record(TaskTiming{10ms, 10ms, 10ms + 300us, 11ms, 20ms, 0});  // interval 10.3 ms
  s.record(TaskTiming{20ms, 20ms, 20ms + 100us, 21ms, 30ms, 0});  // interval 9.8 ms
  EXPECT_EQ(s.period_jitter().count(), 2U) << "the first run has no interval";
  EXPECT_EQ(s.period_jitter().max(), 300us);
  EXPECT_EQ(s.start_latency().max(), 300us);
}
