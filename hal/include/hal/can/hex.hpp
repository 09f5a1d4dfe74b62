#pragma once
// Hex digits of CAN text formats (candump logs, cansend notation, slcan).
#include <cstdint>
#include <string>

namespace hal::hex {

// Value of one hex digit (either case), or -1.
constexpr int digit_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

// Appends `len` data bytes as upper-case hex pairs.
inline void append_bytes(std::string& out, const uint8_t* bytes, size_t len) {
  static constexpr char kDigits[] = "0123456789ABCDEF";
  for (size_t i = 0; i < len; ++i) {
    out += kDigits[bytes[i] >> 4];
    out += kDigits[bytes[i] & 0xF];
  }
}

}  // namespace hal::hex
