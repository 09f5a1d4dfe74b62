// The fixed-rate executor on the simulated clock: rates, no drift, overrun/skip accounting, the
// 100 Hz deadline under a slow 10 Hz task, determinism.
#include <gtest/gtest.h>

#include <array>
#include <thread>
#include <vector>

#include "firmware/scheduler/executor.hpp"
#include "hal/sim_clock.hpp"

using namespace std::chrono_literals;
using core::Nanos;
using firmware::Executor;
using firmware::TaskBinding;

namespace {

constexpr std::array<core::GroupSpec, 2> kGroups{{{"fast", 40}, {"slow", 20}}};

// Runs `ex` single-threaded on `clock` from `origin` until virtual time `end` (inclusive).
void run_single_until(Executor& ex, hal::SimClock& clock, Nanos origin, Nanos end) {
  clock.set_horizon(end);
  std::thread stopper([&] {
    clock.wait_until_idle_at(end);
    ex.stop();
  });
  ex.run(origin);
  stopper.join();
}

void run_threaded_until(Executor& ex, hal::SimClock& clock, Nanos origin, Nanos end) {
  clock.set_horizon(end);
  ex.start(origin, /*realtime=*/false);
  clock.wait_until_idle_at(end);
  ex.stop();
}

struct Event {
  std::string_view task;
  Nanos now;
  Nanos period;
  bool operator==(const Event&) const = default;
};

}  // namespace

TEST(Executor, EachTaskRunsAtItsExactRate) {
  hal::SimClock clock;
  std::vector<TaskBinding> tasks;
  for (const uint32_t rate : {120U, 100U, 50U, 30U, 10U}) {
    tasks.push_back({core::TaskSpec{"t", rate, 1000, 0, 0}, [](const core::Tick&) {}});
  }
  Executor ex(clock, kGroups, std::move(tasks));
  run_single_until(ex, clock, 0s, 10s);
  const std::array<uint64_t, 5> expected{1201, 1001, 501, 301, 101};  // releases in [0, 10 s]
  for (size_t i = 0; i < ex.task_count(); ++i) {
    EXPECT_EQ(ex.stats(i).runs(), expected[i]) << ex.spec(i).rate_hz << " Hz";
    EXPECT_EQ(ex.stats(i).overruns(), 0U);
    EXPECT_EQ(ex.stats(i).skipped(), 0U);
  }
}

TEST(Executor, NoDriftOverALongRun) {
  hal::SimClock clock;
  std::vector<Nanos> starts;
  Executor ex(clock, kGroups,
              {{core::TaskSpec{"tracker", 120, 300, 0, 0},
                [&](const core::Tick& t) { starts.push_back(t.now); }}});
  run_single_until(ex, clock, 1s, 1s + 1000s);
  ASSERT_EQ(starts.size(), 120001U);
  EXPECT_EQ(starts.front(), 1s);
  EXPECT_EQ(starts[120], 2s);
  EXPECT_EQ(starts.back(), 1001s) << "the 120000th period ends exactly 1000 s later";
  EXPECT_EQ(ex.stats(0).period_jitter().max(), Nanos(1)) << "periods are 8333333 or 8333334 ns";
}

TEST(Executor, TasksAreToldTheirTimeAndPeriod) {
  hal::SimClock clock;
  std::vector<core::Tick> ticks;
  Executor ex(clock, kGroups,
              {{core::TaskSpec{"control", 100, 3000, 0, 0},
                [&](const core::Tick& t) { ticks.push_back(t); }}});
  run_single_until(ex, clock, 0s, 30ms);
  ASSERT_EQ(ticks.size(), 4U);
  EXPECT_EQ(ticks[0].now, 0ms);
  EXPECT_EQ(ticks[0].period, 10ms) << "nominal period on the first run";
  EXPECT_EQ(ticks[3].now, 30ms);
  EXPECT_EQ(ticks[3].period, 10ms);
  EXPECT_EQ(ticks[3].release, 30ms);
}

TEST(Executor, CountsOverrunsSkipsAndBudgetExceedances) {
  hal::SimClock clock;
  // A 100 Hz task that takes 15 ms of (virtual) time each run.
  Executor ex(clock, kGroups, {{core::TaskSpec{"slow", 100, 5000, 0, 0}, [&](const core::Tick& t) {
                                  clock.sleep_until(t.now + 15ms);
                                }}});
  run_single_until(ex, clock, 0s, 1s);
  const auto& s = ex.stats(0);
  EXPECT_GT(s.runs(), 0U);
  // Every run ends after the next release, but the last one, cut short by the stop.
  EXPECT_EQ(s.overruns(), s.runs() - 1);
  EXPECT_GE(s.budget_exceeded(), s.runs() - 1);
  EXPECT_EQ(s.runs() + s.skipped(), 100U) << "every release is either run or skipped";
  EXPECT_EQ(s.run_time().max(), 15ms);
}

// The design point of rate groups: a 10 Hz task that runs for 80 ms must not delay the 100 Hz
// control task by a single nanosecond when they are in different groups (threads).
TEST(Executor, HundredHertzDeadlineHoldsWhileALongTenHertzTaskRuns) {
  hal::SimClock clock;
  std::atomic<int> lidar_runs{0};
  std::vector<TaskBinding> tasks{
      {core::TaskSpec{"control", 100, 3000, 0, 10}, [](const core::Tick&) {}},
      {core::TaskSpec{"supervisor", 100, 50, 0, 20}, [](const core::Tick&) {}},
      {core::TaskSpec{"lidar", 10, 5000, 1, 0},
       [&](const core::Tick& t) {
         ++lidar_runs;
         clock.sleep_until(t.now + 80ms);  // 80 ms of work
       }},
  };
  Executor ex(clock, kGroups, tasks);
  run_threaded_until(ex, clock, 0s, 2s);
  const auto& control = ex.stats(ex.find("control"));
  EXPECT_EQ(control.runs(), 201U);
  EXPECT_EQ(control.overruns(), 0U);
  EXPECT_EQ(control.skipped(), 0U);
  EXPECT_EQ(control.start_latency().max(), 0ns);
  EXPECT_EQ(control.period_jitter().max(), 0ns);
  EXPECT_GE(lidar_runs.load(), 20);
  EXPECT_EQ(ex.stats(ex.find("lidar")).budget_exceeded(), ex.stats(ex.find("lidar")).runs() - 1)
      << "every lidar run but the one cut short by the stop";

  // The same table on one thread: the lidar run blocks control, which misses releases. This is
  // what the rate groups prevent (and proves the test above can fail).
  hal::SimClock clock1;
  std::vector<TaskBinding> tasks1 = tasks;
  tasks1[2].fn = [&](const core::Tick& t) { clock1.sleep_until(t.now + 80ms); };
  Executor single(clock1, kGroups, tasks1);
  run_single_until(single, clock1, 0s, 2s);
  EXPECT_GT(single.stats(single.find("control")).skipped(), 100U);
  EXPECT_GE(single.stats(single.find("control")).start_latency().max(), 70ms);
}

TEST(Executor, SingleThreadModeIsDeterministic) {
  auto run_once = [] {
    hal::SimClock clock(5s);
    std::vector<Event> events;
    uint64_t state = 1;
    auto task = [&](std::string_view name, uint32_t rate, uint8_t prio, Nanos work) {
      return TaskBinding{
          core::TaskSpec{name, rate, 1000, 0, prio}, [&, name, work](const core::Tick& t) {
            events.push_back({name, t.now, t.period});
            state = state * 6364136223846793005ULL + static_cast<uint64_t>(t.now.count());
            if (work > 0ns) clock.sleep_until(t.now + work);
          }};
    };
    Executor ex(clock, kGroups,
                {task("tracker", 120, 90, 0ns), task("base", 50, 80, 200us),
                 task("supervisor", 100, 70, 0ns), task("control", 100, 60, 3ms),
                 task("policy", 30, 50, 1ms), task("lidar", 10, 40, 12ms)});
    run_single_until(ex, clock, 5s, 8s);
    return std::make_pair(events, state);
  };
  const auto a = run_once();
  const auto b = run_once();
  ASSERT_GT(a.first.size(), 1000U);
  EXPECT_EQ(a.first, b.first) << "same task order and times";
  EXPECT_EQ(a.second, b.second) << "same outputs";
  // Tasks due together run in priority order.
  EXPECT_EQ(a.first[0].task, "tracker");
  EXPECT_EQ(a.first[1].task, "base");
  EXPECT_EQ(a.first[2].task, "supervisor");
}

TEST(Executor, ReportsRealTimeOutcomePerGroup) {
  hal::SimClock clock;
  // Priority 60 is outside the allowed 1..49: refused whatever the permissions.
  const std::array<core::GroupSpec, 1> groups{{{"bad", 60}}};
  Executor ex(clock, groups, {{core::TaskSpec{"t", 10, 100, 0, 0}, [](const core::Tick&) {}}});
  clock.set_horizon(0s);
  ex.start(1s, /*realtime=*/true);
  const auto outcomes = ex.rt_outcomes();
  ex.stop();
  ASSERT_EQ(outcomes.size(), 1U);
  EXPECT_EQ(outcomes[0].group, "bad");
  EXPECT_FALSE(outcomes[0].ok);
  EXPECT_NE(outcomes[0].message.find("1..49"), std::string::npos);
}
