#pragma once
// Time in core/ is always passed in, never read: nanoseconds since the monotonic epoch.
#include <chrono>
#include <cstdint>

namespace core {

using Nanos = std::chrono::nanoseconds;
using std::chrono_literals::operator""ms;
using std::chrono_literals::operator""us;
using std::chrono_literals::operator""s;

inline constexpr double to_seconds(Nanos d) {
  return static_cast<double>(d.count()) * 1e-9;
}
inline constexpr double to_ms(Nanos d) {
  return static_cast<double>(d.count()) * 1e-6;
}
inline constexpr double to_us(Nanos d) {
  return static_cast<double>(d.count()) * 1e-3;
}
inline constexpr Nanos from_ms(int64_t ms) {
  return std::chrono::milliseconds(ms);
}

}  // namespace core
