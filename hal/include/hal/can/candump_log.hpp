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

namespace hal {

struct CandumpRecord {
  int64_t sec = 0;   // timestamp as written (usually wall-clock seconds)
  int64_t nsec = 0;  // fractional part in nanoseconds
  std::string iface;
  CanFrame frame;
};

enum class CandumpParse : uint8_t { kRecord, kIgnored, kMalformed };

// Parses one line; on kMalformed `error` says why.
CandumpParse parse_candump_line(std::string_view line, CandumpRecord& out, std::string& error);
// One line without the newline; `nine_digits` writes nanoseconds instead of microseconds.
std::string format_candump_line(const CandumpRecord& rec, bool nine_digits = false);

class CandumpReader {
 public:
  explicit CandumpReader(const std::string& path);
  [[nodiscard]] bool is_open() const { return in_.is_open(); }
  // Next record; malformed lines are counted and skipped (see malformed(), last_error()).
  std::optional<CandumpRecord> next();
  [[nodiscard]] uint64_t malformed() const { return malformed_; }
  [[nodiscard]] const std::string& last_error() const { return last_error_; }
  [[nodiscard]] uint64_t line_number() const { return line_; }

 private:
  std::ifstream in_;
  uint64_t malformed_ = 0;
  uint64_t line_ = 0;
  std::string last_error_;
};

class CandumpWriter {
 public:
  explicit CandumpWriter(const std::string& path);
  [[nodiscard]] bool is_open() const { return out_.is_open(); }
  void write(const CandumpRecord& rec);
  void flush() { out_.flush(); }

 private:
  std::ofstream out_;
};

}  // namespace hal
