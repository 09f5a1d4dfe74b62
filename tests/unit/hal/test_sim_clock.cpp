#include <gtest/gtest.h>

#include <thread>
#include <vector>

#include "hal/sim_clock.hpp"

using namespace std::chrono_literals;

TEST(SimClock, StartsWhereToldAndOnlyMovesWhenTold) {
  hal::SimClock clock(5s);
  EXPECT_EQ(clock.now(), 5s);
  EXPECT_EQ(clock.now(), 5s);
  clock.advance_by(10ms);
  EXPECT_EQ(clock.now(), 5s + 10ms);
  clock.advance_to(1s);  // never backwards
  EXPECT_EQ(clock.now(), 5s + 10ms);
}

TEST(SimClock, LoneSleeperJumpsToItsDeadline) {
  hal::SimClock clock;
  EXPECT_TRUE(clock.sleep_until(250ms));
  EXPECT_EQ(clock.now(), 250ms);
  EXPECT_TRUE(clock.sleep_until(100ms)) << "a past deadline returns at once";
  EXPECT_EQ(clock.now(), 250ms);
}

TEST(SimClock, AttachedThreadsAdvanceTogetherInDeadlineOrder) {
  hal::SimClock clock;
  std::mutex m;
  std::vector<std::pair<int, hal::Nanos>> events;
  clock.attach_thread();
  clock.attach_thread();
  clock.set_horizon(100ms);
  auto worker = [&](int id, hal::Nanos period) {
    for (hal::Nanos t = period; t <= 100ms; t += period) {
      if (!clock.sleep_until(t)) break;
      std::lock_guard lock(m);
      events.emplace_back(id, clock.now());
    }
    clock.detach_thread();
  };
  std::thread a(worker, 1, 10ms);
  std::thread b(worker, 2, 25ms);
  a.join();
  b.join();
  // Each thread woke exactly at its own deadlines.
  int a_count = 0;
  int b_count = 0;
  for (const auto& [id, t] : events) {
    if (id == 1) {
      EXPECT_EQ(t, ++a_count * 10ms);
    } else {
      EXPECT_EQ(t, ++b_count * 25ms);
    }
  }
  EXPECT_EQ(a_count, 10);
  EXPECT_EQ(b_count, 4);
  EXPECT_EQ(clock.now(), 100ms);
}

TEST(SimClock, HorizonStopsFreeRunningTime) {
  hal::SimClock clock;
  clock.attach_thread();
  clock.set_horizon(50ms);
  std::thread t([&] {
    for (int i = 1; i <= 10; ++i) {
      if (!clock.sleep_until(i * 10ms)) break;
    }
    clock.detach_thread();
  });
  ASSERT_TRUE(clock.wait_until_idle_at(50ms));
  EXPECT_EQ(clock.now(), 50ms);
  EXPECT_EQ(clock.sleepers(), 1U) << "the thread waits for 60 ms beyond the horizon";
  clock.set_horizon(100ms);
  t.join();
  EXPECT_EQ(clock.now(), 100ms);
}

TEST(SimClock, InterruptWakesSleepersWithFalse) {
  hal::SimClock clock;
  clock.attach_thread();
  clock.attach_thread();  // a second participant that never sleeps keeps time still
  bool result = true;
  std::thread t([&] { result = clock.sleep_until(1s); });
  while (clock.sleepers() == 0)
    std::this_thread::yield();
  EXPECT_EQ(clock.now(), 0s);
  clock.interrupt();
  t.join();
  EXPECT_FALSE(result);
  EXPECT_EQ(clock.sleepers(), 0U);
}
