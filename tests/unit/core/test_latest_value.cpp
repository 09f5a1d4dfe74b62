#include <gtest/gtest.h>

#include <atomic>
#include <thread>
#include <vector>

#include "core/channel/latest_value.hpp"

using namespace std::chrono_literals;

namespace {
struct Pose {
  double x = 0;
  double y = 0;
  double theta = 0;
  int64_t seq = 0;
  int64_t check = 0;  // == -seq: a torn read would mix two writes
};
}  // namespace

TEST(LatestValue, EmptyUntilTheFirstPublish) {
  core::LatestValue<Pose> ch;
  EXPECT_FALSE(ch.read().has_value());
  EXPECT_EQ(ch.published(), 0U);
}

TEST(LatestValue, ReturnsTheLatestValueWithItsStampAndCount) {
  core::LatestValue<Pose> ch;
  ch.publish(Pose{1, 2, 3, 1, -1}, 10ms);
  ch.publish(Pose{4, 5, 6, 2, -2}, 20ms);
  const auto r = ch.read();
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->value.x, 4);
  EXPECT_EQ(r->value.theta, 6);
  EXPECT_EQ(r->stamp, 20ms);
  EXPECT_EQ(r->count, 2U);
  EXPECT_EQ(r->age(25ms), 5ms);
  EXPECT_EQ(ch.published(), 2U);
}

// One writer, several readers hammering the channel: every read is one whole write, and counts
// never go backwards for a reader. Run under ThreadSanitizer in CI (label: concurrency).
TEST(LatestValue, ConcurrentReadersNeverSeeATornValue) {
  core::LatestValue<Pose> ch;
  constexpr int64_t kWrites = 200000;
  std::atomic<bool> done{false};
  std::atomic<int64_t> torn{0};
  std::atomic<int64_t> reads{0};
  std::atomic<int> started{0};
  std::vector<std::thread> readers;
  for (int r = 0; r < 3; ++r) {
    readers.emplace_back([&] {
      uint64_t last_count = 0;
      started.fetch_add(1);
      do {
        const auto v = ch.read();
        if (!v) continue;
        reads.fetch_add(1, std::memory_order_relaxed);
        const Pose& p = v->value;
        if (p.check != -p.seq || p.x != static_cast<double>(p.seq) ||
            v->stamp != core::Nanos(p.seq) || v->count != static_cast<uint64_t>(p.seq) ||
            v->count < last_count) {
          torn.fetch_add(1);
        }
        last_count = v->count;
      } while (!done.load(std::memory_order_acquire));
    });
  }
  ch.publish(Pose{1, 0, 0, 1, -1}, core::Nanos(1));
  while (started.load() < 3)
    std::this_thread::yield();  // overlap writes with reads
  for (int64_t i = 2; i <= kWrites; ++i) {
    ch.publish(Pose{static_cast<double>(i), 0, 0, i, -i}, core::Nanos(i));
  }
  done = true;
  for (auto& t : readers)
    t.join();
  EXPECT_EQ(torn.load(), 0);
  EXPECT_GT(reads.load(), 0);
  EXPECT_EQ(ch.read()->count, static_cast<uint64_t>(kWrites));
}
