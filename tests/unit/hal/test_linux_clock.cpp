#include <gtest/gtest.h>
#include <pthread.h>

#include <atomic>
#include <csignal>
#include <thread>

#include "hal/linux_clock.hpp"

using namespace std::chrono_literals;

TEST(LinuxClock, IsMonotonic) {
  hal::LinuxClock clock;
  hal::Nanos prev = clock.now();
  for (int i = 0; i < 10000; ++i) {
    const hal::Nanos t = clock.now();
    ASSERT_GE(t, prev);
    prev = t;
  }
}

TEST(LinuxClock, SleepUntilPastDeadlineReturnsAtOnce) {
  hal::LinuxClock clock;
  const hal::Nanos before = clock.now();
  EXPECT_TRUE(clock.sleep_until(before - 1s));
  EXPECT_LT(clock.now() - before, 50ms);
}

TEST(LinuxClock, SleepsToTheAbsoluteDeadline) {
  hal::LinuxClock clock;
  const hal::Nanos deadline = clock.now() + 3ms;
  EXPECT_TRUE(clock.sleep_until(deadline));
  EXPECT_GE(clock.now(), deadline);
}

TEST(LinuxClock, SleepsBeyondOneSliceWithoutDrift) {
  hal::LinuxClock clock;
  const hal::Nanos deadline = clock.now() + hal::LinuxClock::kMaxSleepSlice + 20ms;
  EXPECT_TRUE(clock.sleep_until(deadline));
  EXPECT_GE(clock.now(), deadline);
}

namespace {
std::atomic<int> g_signals{0};
void count_signal(int /*sig*/) {
  g_signals.fetch_add(1);
}
}  // namespace

TEST(LinuxClock, RetriesOnEintrAndStillReachesDeadline) {
  struct sigaction sa {};
  sa.sa_handler = count_signal;  // no SA_RESTART: clock_nanosleep returns EINTR
  sigemptyset(&sa.sa_mask);
  struct sigaction old {};
  ASSERT_EQ(sigaction(SIGUSR1, &sa, &old), 0);

  hal::LinuxClock clock;
  const hal::Nanos deadline = clock.now() + 200ms;
  std::atomic<bool> asleep{false};
  std::atomic<bool> done{false};
  hal::Nanos woke{0};
  std::thread sleeper([&] {
    asleep = true;
    EXPECT_TRUE(clock.sleep_until(deadline));
    woke = clock.now();
    done = true;
  });
  while (!asleep)
    std::this_thread::yield();
  // Interrupt the sleep with signals until the sleeper is done.
  while (!done) {
    pthread_kill(sleeper.native_handle(), SIGUSR1);
    hal::LinuxClock().sleep_until(hal::monotonic_now() + 5ms);
  }
  sleeper.join();
  sigaction(SIGUSR1, &old, nullptr);
  EXPECT_GT(g_signals.load(), 0);
  EXPECT_GE(woke, deadline);
}

TEST(LinuxClock, InterruptWakesASleeperPromptly) {
  hal::LinuxClock clock;
  bool result = true;
  const hal::Nanos start = clock.now();
  std::thread sleeper([&] { result = clock.sleep_until(clock.now() + 30s); });
  clock.interrupt();
  sleeper.join();
  EXPECT_FALSE(result);
  EXPECT_LT(clock.now() - start, 1s);
  EXPECT_FALSE(clock.sleep_until(clock.now() + 1s)) << "sleeps after interrupt return at once";
}
