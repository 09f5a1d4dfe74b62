#pragma once
// The text line shared by candump logs and our tracker captures:
//   (1699999999.123456) <interface> <payload>
// 6 or 9 fractional digits; lines not starting with '(' are comments.
#include <cstdint>
#include <string>
#include <string_view>

namespace hal {

enum class LogLineParse : uint8_t { kRecord, kIgnored, kMalformed };

struct LogLine {
  int64_t sec = 0;
  int64_t nsec = 0;
  std::string_view iface;
  std::string_view payload;  // up to the next space (trailing annotations are ignored)
};

LogLineParse split_log_line(std::string_view line, LogLine& out, std::string& error);
// "(sec.usec) iface " (or nanoseconds with nine_digits), ready for the payload.
std::string log_line_prefix(int64_t sec, int64_t nsec, std::string_view iface, bool nine_digits);

}  // namespace hal
