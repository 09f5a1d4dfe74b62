#pragma once
// Immutable snapshots of a large value (the costmap) from one writer task to any number of
// reader tasks, lock-free. The writer fills a buffer no reader holds, then publishes it; a reader
// pins the newest published buffer and keeps it as long as it holds the handle (it never changes
// under it). Buffers are allocated once (a small pool); nothing allocates afterwards. If every
// spare buffer is pinned, begin_write() returns nullptr and the writer skips that update
// (counted).
//
// Pinning: a reader increments the slot's reader count, then checks the slot is still the
// published one (else it unpins and retries). The writer only writes a slot that is not published
// and has no readers, so a reader that passes the check sees a completely written slot.
#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>

namespace core {

template <typename T>
class SnapshotChannel {
 public:
  // A pinned snapshot (move-only); empty before the first publish.
  class Handle {
   public:
    Handle() = default;
    Handle(const Handle&) = delete;
    Handle& operator=(const Handle&) = delete;
    Handle(Handle&& o) noexcept : value_(o.value_), count_(o.count_) {
      o.value_ = nullptr;
      o.count_ = nullptr;
    }
    Handle& operator=(Handle&& o) noexcept {
      if (this != &o) {
        release();
        value_ = o.value_;
        count_ = o.count_;
        o.value_ = nullptr;
        o.count_ = nullptr;
      }
      return *this;
    }
    ~Handle() { release(); }
    explicit operator bool() const { return value_ != nullptr; }
    const T* get() const { return value_; }
    const T& operator*() const { return *value_; }
    const T* operator->() const { return value_; }

   private:
    friend class SnapshotChannel;
    Handle(const T* v, std::atomic<int>* c) : value_(v), count_(c) {}
    void release() {
      if (count_ != nullptr) count_->fetch_sub(1);
      value_ = nullptr;
      count_ = nullptr;
    }
    const T* value_ = nullptr;
    std::atomic<int>* count_ = nullptr;
  };

  // `buffers` >= 2: one published, the others to write; more when readers hold snapshots long.
  explicit SnapshotChannel(const T& initial = T{}, size_t buffers = 4)
      : slots_(buffers < 2 ? 2 : buffers) {
    for (Slot& s : slots_)
      s.value = std::make_unique<T>(initial);
  }

  // Writer: a buffer to fill (holding that buffer's previous contents), or nullptr.
  T* begin_write() {
    const int current = latest_.load();
    for (size_t i = 0; i < slots_.size(); ++i) {
      if (static_cast<int>(i) != current && slots_[i].readers.load() == 0) {
        writing_ = static_cast<int>(i);
        return slots_[i].value.get();
      }
    }
    ++skipped_;
    return nullptr;
  }
  // Writer: makes the buffer from begin_write() the newest snapshot.
  void publish() {
    if (writing_ < 0) return;
    latest_.store(writing_);
    writing_ = -1;
    published_.fetch_add(1);
  }

  // Readers: the newest snapshot (empty handle before the first publish).
  [[nodiscard]] Handle latest() const {
    for (;;) {
      const int i = latest_.load();
      if (i < 0) return Handle();
      Slot& s = slots_[static_cast<size_t>(i)];
      s.readers.fetch_add(1);
      if (latest_.load() == i) return Handle(s.value.get(), &s.readers);
      s.readers.fetch_sub(1);  // replaced meanwhile: pin the newer one
    }
  }
  [[nodiscard]] uint64_t published() const { return published_.load(); }
  [[nodiscard]] uint64_t skipped() const { return skipped_; }  // writer side

 private:
  struct Slot {
    std::unique_ptr<T> value;
    mutable std::atomic<int> readers{0};
  };
  mutable std::vector<Slot> slots_;
  std::atomic<int> latest_{-1};
  int writing_ = -1;
  std::atomic<uint64_t> published_{0};
  uint64_t skipped_ = 0;
};

}  // namespace core
