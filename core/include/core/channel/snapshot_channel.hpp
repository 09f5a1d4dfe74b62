#pragma once
// Immutable snapshots of a large value (the costmap) from one writer task to any number of
// reader tasks. The writer fills a buffer no reader holds, then publishes it; a reader gets a
// shared pointer to the newest published buffer and keeps it as long as it likes (it never
// changes under it). Buffers are allocated once (a small pool); publishing and reading do not
// allocate. If every spare buffer is still held by readers, begin_write() returns nullptr and the
// writer skips this update (counted).
#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>

namespace core {

template <typename T>
class SnapshotChannel {
 public:
  // `buffers` >= 2: one published, the others to write; more when readers hold snapshots long.
  explicit SnapshotChannel(const T& initial = T{}, size_t buffers = 4) {
    for (size_t i = 0; i < buffers; ++i)
      pool_.push_back(std::make_shared<T>(initial));
  }

  // Writer: a buffer to fill (holding the previous contents of that buffer), or nullptr.
  T* begin_write() {
    const std::shared_ptr<const T> current = latest_.load(std::memory_order_acquire);
    for (auto& p : pool_) {
      // Only the pool holds it (and it is not the published one): no reader can reach it.
      if (p != current && p.use_count() == 1) {
        writing_ = p;
        return p.get();
      }
    }
    ++skipped_;
    return nullptr;
  }
  // Writer: makes the buffer from begin_write() the newest snapshot.
  void publish() {
    if (!writing_) return;
    latest_.store(std::shared_ptr<const T>(writing_), std::memory_order_release);
    writing_.reset();
    published_.fetch_add(1, std::memory_order_relaxed);
  }

  // Readers: the newest snapshot, or nullptr before the first publish.
  [[nodiscard]] std::shared_ptr<const T> latest() const {
    return latest_.load(std::memory_order_acquire);
  }
  [[nodiscard]] uint64_t published() const { return published_.load(std::memory_order_relaxed); }
  [[nodiscard]] uint64_t skipped() const { return skipped_; }  // writer side

 private:
  std::vector<std::shared_ptr<T>> pool_;
  std::shared_ptr<T> writing_;
  std::atomic<std::shared_ptr<const T>> latest_;
  std::atomic<uint64_t> published_{0};
  uint64_t skipped_ = 0;
};

}  // namespace core
