#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "core/util/histogram.hpp"

using core::DurationHistogram;
using core::Nanos;

TEST(Histogram, BucketsAreMonotonicAndTight) {
  int prev = -1;
  for (uint64_t v = 0; v < 200000; v += 7) {
    const int b = DurationHistogram::bucket_of(v);
    ASSERT_GE(b, prev);
    ASSERT_LT(b, DurationHistogram::kBuckets);
    const uint64_t upper = DurationHistogram::bucket_upper(b);
    ASSERT_GE(upper, v);
    // Upper edge within 1/32 of the value (exact below 64).
    ASSERT_LE(static_cast<double>(upper - v), static_cast<double>(v) / 32.0 + 1e-9) << v;
    prev = b;
  }
  EXPECT_LT(DurationHistogram::bucket_of(UINT64_MAX), DurationHistogram::kBuckets);
}

TEST(Histogram, QuantilesOfAKnownDistribution) {
  DurationHistogram h;
  EXPECT_EQ(h.quantile(0.5), Nanos(0));
  std::vector<int64_t> values;
  std::mt19937 rng(42);
  std::uniform_int_distribution<int64_t> dist(1000, 2'000'000);
  for (int i = 0; i < 20000; ++i)
    values.push_back(dist(rng));
  for (const auto v : values)
    h.record(Nanos(v));
  std::sort(values.begin(), values.end());
  for (const double q : {0.5, 0.9, 0.99}) {
    const auto exact = static_cast<double>(
        values[static_cast<size_t>(q * static_cast<double>(values.size())) - 1]);
    const auto got = static_cast<double>(h.quantile(q).count());
    EXPECT_GE(got, exact * 0.999) << q;
    EXPECT_LE(got, exact * 1.04) << q;
  }
  EXPECT_EQ(h.max(), Nanos(values.back()));
  EXPECT_EQ(h.quantile(1.0), h.max());
  EXPECT_EQ(h.count(), 20000U);
  h.reset();
  EXPECT_EQ(h.count(), 0U);
  EXPECT_EQ(h.max(), Nanos(0));
}

TEST(Histogram, NegativeDurationsCountAsZero) {
  DurationHistogram h;
  h.record(Nanos(-5));
  EXPECT_EQ(h.count(), 1U);
  EXPECT_EQ(h.quantile(0.5), Nanos(0));
}
