#include "core/util/histogram.hpp"

#include <algorithm>
#include <bit>
#include <cmath>

namespace core {

int DurationHistogram::bucket_of(uint64_t v) {
  if (v < static_cast<uint64_t>(kSubBuckets)) return static_cast<int>(v);
  const int msb = 63 - std::countl_zero(v);
  const int shift = msb - kSubBucketBits;  // >= 0
  // (v >> shift) is in [32, 63]: the top 6 bits; bucket = shift * 32 + that.
  return shift * kSubBuckets + static_cast<int>(v >> shift);
}

uint64_t DurationHistogram::bucket_upper(int bucket) {
  if (bucket < 2 * kSubBuckets) return static_cast<uint64_t>(bucket);
  const int shift = bucket / kSubBuckets - 1;
  const uint64_t top = static_cast<uint64_t>(bucket - shift * kSubBuckets);
  // Largest value whose top bits equal `top` at this shift.
  return ((top + 1) << shift) - 1;
}

void DurationHistogram::record(Nanos value) {
  const int64_t ns = std::max<int64_t>(value.count(), 0);
  const int b = bucket_of(static_cast<uint64_t>(ns));
  // Single writer: load+store is race-free and cheaper than fetch_add.
  auto& slot = buckets_[static_cast<size_t>(b)];
  slot.store(slot.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
  count_.store(count_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
  if (ns > max_ns_.load(std::memory_order_relaxed)) max_ns_.store(ns, std::memory_order_relaxed);
}

void DurationHistogram::reset() {
  for (auto& b : buckets_)
    b.store(0, std::memory_order_relaxed);
  count_.store(0, std::memory_order_relaxed);
  max_ns_.store(0, std::memory_order_relaxed);
}

Nanos DurationHistogram::quantile(double q) const {
  uint64_t total = 0;
  for (const auto& b : buckets_)
    total += b.load(std::memory_order_relaxed);
  if (total == 0) return Nanos(0);
  q = std::clamp(q, 0.0, 1.0);
  const auto rank =
      std::max<uint64_t>(1, static_cast<uint64_t>(std::ceil(q * static_cast<double>(total))));
  uint64_t seen = 0;
  for (int i = 0; i < kBuckets; ++i) {
    seen += buckets_[static_cast<size_t>(i)].load(std::memory_order_relaxed);
    if (seen >= rank) {
      const auto upper = static_cast<int64_t>(bucket_upper(i));
      return Nanos(std::min(upper, max_ns_.load(std::memory_order_relaxed)));
    }
  }
  return max();
}

}  // namespace core
