#pragma once
// Fixed-memory log-linear histogram of non-negative durations (HdrHistogram-style buckets:
// 32 linear sub-buckets per power of two, so any quantile is reported within ~3 %).
// Single writer, any number of concurrent readers: counters are relaxed atomics, so a reader
// sees a consistent-enough snapshot without locks and without data races. No allocation.
#include <array>
#include <atomic>
#include <cstdint>

#include "core/time.hpp"

namespace core {

class DurationHistogram {
 public:
  static constexpr int kSubBucketBits = 5;
  static constexpr int kSubBuckets = 1 << kSubBucketBits;  // 32
  static constexpr int kBuckets = (64 - kSubBucketBits) * kSubBuckets + kSubBuckets;

  void record(Nanos value);
  void reset();

  [[nodiscard]] uint64_t count() const { return count_.load(std::memory_order_relaxed); }
  [[nodiscard]] Nanos max() const { return Nanos(max_ns_.load(std::memory_order_relaxed)); }
  // Upper edge of the bucket holding the q-quantile (q in [0, 1]); 0 when empty. Never below
  // the true quantile, never above max().
  [[nodiscard]] Nanos quantile(double q) const;

  // Bucket arithmetic, exposed for tests.
  static int bucket_of(uint64_t value_ns);
  static uint64_t bucket_upper(int bucket);

 private:
  std::array<std::atomic<uint32_t>, kBuckets> buckets_{};
  std::atomic<uint64_t> count_{0};
  std::atomic<int64_t> max_ns_{0};
};

}  // namespace core
