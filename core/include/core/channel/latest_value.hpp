#pragma once
// Timestamped latest-value channel between tasks: exactly one writer task, any number of
// readers, never blocks, never tears.
//
// A sequence lock over storage made of atomic words: the writer makes the sequence odd, stores
// the words (release), makes it even; a reader loads the words (acquire) and retries when the
// sequence was odd or changed under it. All shared accesses are atomic and ordered without
// fences, so there is no data race in the C++ model and ThreadSanitizer can check it; T only has
// to be trivially copyable. Large values (costmaps) use double buffers
// of their own instead of this.
#include <array>
#include <atomic>
#include <cstdint>
#include <cstring>
#include <optional>
#include <type_traits>

#include "core/time.hpp"

namespace core {

template <typename T>
struct Stamped {
  T value;
  Nanos stamp;     // when the value was true (measurement/computation time, monotonic)
  uint64_t count;  // how many values the writer has published, this one included (>= 1)

  [[nodiscard]] Nanos age(Nanos now) const { return now - stamp; }
};

template <typename T>
class LatestValue {
  static_assert(std::is_trivially_copyable_v<T>, "channel values are copied word by word");
  static_assert(std::is_default_constructible_v<T>, "readers build a T to copy into");

 public:
  // Writer side (one task only).
  void publish(const T& value, Nanos stamp) {
    Payload p{value, stamp.count(), ++published_};
    std::array<uint64_t, kWords> words{};
    std::memcpy(words.data(), &p, sizeof(Payload));
    const uint64_t seq = seq_.load(std::memory_order_relaxed);
    seq_.store(seq + 1, std::memory_order_relaxed);
    // Release stores: a reader that sees any new word also sees the odd sequence before it.
    for (size_t i = 0; i < kWords; ++i)
      words_[i].store(words[i], std::memory_order_release);
    seq_.store(seq + 2, std::memory_order_release);
  }

  // Reader side (any thread). Empty until the first publish.
  [[nodiscard]] std::optional<Stamped<T>> read() const {
    std::array<uint64_t, kWords> words{};
    for (;;) {
      const uint64_t s1 = seq_.load(std::memory_order_acquire);
      if (s1 == 0) return std::nullopt;
      if (s1 & 1U) continue;  // write in progress
      // Acquire loads keep the re-check of the sequence after them.
      for (size_t i = 0; i < kWords; ++i)
        words[i] = words_[i].load(std::memory_order_acquire);
      if (seq_.load(std::memory_order_relaxed) == s1) break;
    }
    Payload p;
    std::memcpy(static_cast<void*>(&p), words.data(), sizeof(Payload));
    return Stamped<T>{p.value, Nanos(p.stamp_ns), p.count};
  }

  // Number of publishes so far (writer's view; readers use Stamped::count).
  [[nodiscard]] uint64_t published() const { return seq_.load(std::memory_order_acquire) / 2; }

 private:
  struct Payload {
    T value{};
    int64_t stamp_ns = 0;
    uint64_t count = 0;
  };
  static constexpr size_t kWords = (sizeof(Payload) + sizeof(uint64_t) - 1) / sizeof(uint64_t);

  std::atomic<uint64_t> seq_{0};
  std::array<std::atomic<uint64_t>, kWords> words_{};
  uint64_t published_ = 0;  // writer-only
};

}  // namespace core
