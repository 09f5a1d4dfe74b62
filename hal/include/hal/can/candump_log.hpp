#pragma once
// candump log files (`candump -l`, read by `canplayer`, `log2asc`):
//   (1699999999.123456) can0 111#0096000000000000
// Standard ids as 3 hex digits, extended as 8, `#R` for remote frames, error frames as extended
// ids with 0x20000000 (CAN_ERR_FLAG) set. 6 or 9 fractional digits. Lines not starting with '('
// are ignored (comments). CAN FD (`##`) is reported as unsupported.
#include <cstdint>
#include <fstream>
#include <optional>
#include <string>
#include <string_view>

#include "hal/can/can_frame.hpp"
#include "hal/capture/log_line.hpp"

namespace hal {

struct CandumpRecord {
  int64_t sec = 0;   // timestamp as written (usually wall-clock seconds)
  int64_t nsec = 0;  // fractional part in nanoseconds
  std::string iface;
  CanFrame frame;
};

using CandumpParse = LogLineParse;  // kRecord, kIgnored, kMalformed

// Parses one line; on kMalformed `error` says why.
CandumpParse parse_candump_line(std::string_view line, CandumpRecord& out, std::string& error);
// One line without the newline; `nine_digits` writes nanoseconds instead of microseconds.
std::string format_candump_line(const CandumpRecord& rec, bool nine_digits = false);

using CandumpReader = LineLogReader<CandumpRecord, parse_candump_line>;
using CandumpWriter = LineLogWriter<CandumpRecord, format_candump_line>;

}  // namespace hal
