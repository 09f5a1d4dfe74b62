#pragma once
// Hysteresis in time for a safety condition: it asserts at once when its raw test trips (stop
// fast) and clears only after the raw test has stayed clear for `clear_after` (resume slowly,
// no chattering on a flickering signal).
#include "core/time.hpp"

namespace core {

class Debounce {
 public:
  Debounce() = default;
  explicit Debounce(Nanos clear_after) : clear_after_(clear_after) {}

  // Returns the debounced state.
  bool update(bool raw, Nanos now) {
    if (raw) {
      asserted_ = true;
      clear_since_valid_ = false;
    } else if (asserted_) {
      if (!clear_since_valid_) {
        clear_since_ = now;
        clear_since_valid_ = true;
      }
      if (now - clear_since_ >= clear_after_) asserted_ = false;
    }
    return asserted_;
  }
  [[nodiscard]] bool asserted() const { return asserted_; }
  void set_clear_after(Nanos d) { clear_after_ = d; }

 private:
  Nanos clear_after_{0};
  Nanos clear_since_{0};
  bool clear_since_valid_ = false;
  bool asserted_ = false;
};

}  // namespace core
