#pragma once
#include <cstdint>

namespace core {

// floor() to an integer without the libm call (the baseline x86-64 / aarch64 targets do not
// inline it); for finite values within int64_t's range.
inline int64_t floor_to_int(double v) {
  const auto i = static_cast<int64_t>(v);
  return i - static_cast<int64_t>(v < static_cast<double>(i));  // branchless
}

}  // namespace core
