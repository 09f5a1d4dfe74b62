#include <gtest/gtest.h>

#include "core/safety/debounce.hpp"
#include "core/util/rate_limiter.hpp"

using namespace std::chrono_literals;

TEST(Debounce, AssertsAtOnceAndClearsAfterStayingClear) {
  core::Debounce d(100ms);
  EXPECT_FALSE(d.update(false, 0ms));
  EXPECT_TRUE(d.update(true, 10ms));
  EXPECT_TRUE(d.update(false, 20ms));
  EXPECT_TRUE(d.update(false, 110ms));
  EXPECT_TRUE(d.update(true, 115ms)) << "flicker restarts the clear time";
  EXPECT_TRUE(d.update(false, 120ms));
  EXPECT_TRUE(d.update(false, 219ms));
  EXPECT_FALSE(d.update(false, 220ms));
}

TEST(RateLimiter, EmitsOncePerIntervalAndCountsTheRest) {
  core::RateLimiter r(1s);
  EXPECT_TRUE(r.check(0ms).emit);
  for (int i = 1; i < 100; ++i)
    EXPECT_FALSE(r.check(i * 10ms).emit);
  const auto d = r.check(1000ms);
  EXPECT_TRUE(d.emit);
  EXPECT_EQ(d.suppressed, 99U);
  EXPECT_FALSE(r.check(1500ms).emit);
  const auto d2 = r.check(2000ms);
  EXPECT_TRUE(d2.emit);
  EXPECT_EQ(d2.suppressed, 1U);
}
