// SnapshotChannel: readers always see a complete, unchanging snapshot while the writer keeps
// publishing (run under ThreadSanitizer in CI).
#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <thread>

#include "core/channel/snapshot_channel.hpp"

namespace {

struct Big {
  std::array<uint32_t, 4096> v{};  // every element equals the version: torn = mixed values
};

TEST(SnapshotChannel, EmptyUntilPublishedThenTheNewest) {
  core::SnapshotChannel<Big> ch;
  EXPECT_FALSE(ch.latest());
  Big* b = ch.begin_write();
  ASSERT_NE(b, nullptr);
  b->v.fill(1);
  ch.publish();
  ASSERT_TRUE(ch.latest());
  EXPECT_EQ(ch.latest()->v[100], 1U);
  EXPECT_EQ(ch.published(), 1U);
}

TEST(SnapshotChannel, AHeldSnapshotNeverChangesAndTheWriterSkipsWhenAllAreHeld) {
  core::SnapshotChannel<Big> ch(Big{}, 2);
  ch.begin_write()->v.fill(1);
  ch.publish();
  const auto held = ch.latest();  // a reader keeps version 1 pinned
  Big* b = ch.begin_write();
  ASSERT_NE(b, nullptr);
  EXPECT_NE(b, held.get());
  b->v.fill(2);
  ch.publish();
  const auto held2 = ch.latest();  // and version 2
  EXPECT_EQ(ch.begin_write(), nullptr) << "both buffers are held";
  EXPECT_EQ(ch.skipped(), 1U);
  EXPECT_EQ(held->v[0], 1U);
  EXPECT_EQ(held2->v[0], 2U);
}

TEST(SnapshotChannel, ConcurrentReadersNeverSeeATornSnapshot) {
  core::SnapshotChannel<Big> ch;
  std::atomic<bool> stop{false};
  std::atomic<uint64_t> torn{0};
  std::atomic<uint64_t> reads{0};
  std::vector<std::thread> readers;
  for (int r = 0; r < 2; ++r) {
    readers.emplace_back([&] {
      while (!stop.load()) {
        if (auto s = ch.latest()) {
          const uint32_t first = s->v.front();
          for (uint32_t x : s->v) {
            if (x != first) ++torn;
          }
          ++reads;
        }
      }
    });
  }
  for (uint32_t version = 1; version <= 3000; ++version) {
    if (Big* b = ch.begin_write()) {
      b->v.fill(version);
      ch.publish();
    }
  }
  while (reads.load() < 100) {
    // let the readers run a little (spin on their own progress counter, not on time)
    std::this_thread::yield();
  }
  stop = true;
  for (auto& t : readers)
    t.join();
  EXPECT_EQ(torn.load(), 0U);
  EXPECT_GT(ch.published(), 1000U);
}

}  // namespace
