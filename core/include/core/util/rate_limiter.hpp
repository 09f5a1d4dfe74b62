#pragma once
// Rate limiting of repeated messages (log warnings): at most one every `min_interval`; the ones
// held back are counted so the next emitted line can say "(N suppressed)". Time is passed in.
#include <cstdint>

#include "core/time.hpp"

namespace core {

class RateLimiter {
 public:
  explicit RateLimiter(Nanos min_interval) : min_interval_(min_interval) {}

  struct Decision {
    bool emit;
    uint64_t suppressed;  // messages held back since the previous emitted one (when emit)
  };

  Decision check(Nanos now) {
    if (!has_emitted_ || now - last_emit_ >= min_interval_) {
      const uint64_t held = suppressed_;
      suppressed_ = 0;
      last_emit_ = now;
      has_emitted_ = true;
      return {true, held};
    }
    ++suppressed_;
    return {false, 0};
  }

 private:
  Nanos min_interval_;
  Nanos last_emit_{0};
  bool has_emitted_ = false;
  uint64_t suppressed_ = 0;
};

}  // namespace core
