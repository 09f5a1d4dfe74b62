#include <gtest/gtest.h>

#include "core/scheduler/release_schedule.hpp"

using namespace std::chrono_literals;
using core::Nanos;
using core::ReleaseSchedule;

TEST(ReleaseSchedule, ReleasesAreExactMultiplesOfTheRateWithoutDrift) {
  const ReleaseSchedule s(120, 1s);
  EXPECT_EQ(s.release_at(0), 1s);
  EXPECT_EQ(s.release_at(1), 1s + Nanos(8'333'333));
  EXPECT_EQ(s.release_at(120), 2s) << "120 periods are exactly one second";
  // One year of 120 Hz releases: still exact (no accumulated rounding).
  const uint64_t year = 120ULL * 3600 * 24 * 365;
  EXPECT_EQ(s.release_at(year), 1s + std::chrono::hours(24 * 365));
  EXPECT_EQ(s.nominal_period(), Nanos(8'333'333));
}

TEST(ReleaseSchedule, OnTimeClaimsServeEachReleaseInTurn) {
  ReleaseSchedule s(100, 0s);
  for (int k = 0; k < 1000; ++k) {
    const Nanos start = s.next_release() + 20us;  // a little late, within the period
    const auto c = s.claim(start);
    ASSERT_EQ(c.release, k * 10ms);
    ASSERT_EQ(c.skipped, 0U);
    ASSERT_EQ(c.following, (k + 1) * 10ms);
  }
}

TEST(ReleaseSchedule, ALateStartSkipsMissedReleasesInsteadOfBursting) {
  ReleaseSchedule s(100, 0s);
  (void)s.claim(0s);
  const auto c = s.claim(35ms);  // releases 10, 20, 30 ms are due; serve 30, skip 10 and 20
  EXPECT_EQ(c.first_due, 10ms);
  EXPECT_EQ(c.release, 30ms);
  EXPECT_EQ(c.skipped, 2U);
  EXPECT_EQ(s.next_release(), 40ms);
}

TEST(ReleaseSchedule, ClaimExactlyAtAReleaseServesThatRelease) {
  ReleaseSchedule s(30, 0s);
  for (int k = 0; k < 300; ++k) {
    const Nanos r = s.next_release();
    const auto c = s.claim(r);
    ASSERT_EQ(c.release, r);
    ASSERT_EQ(c.skipped, 0U);
  }
}
