#pragma once
// The text line shared by candump logs and our tracker captures:
//   (1699999999.123456) <interface> <payload>
// 6 or 9 fractional digits; lines not starting with '(' are comments.
#include <cstdint>
#include <fstream>
#include <optional>
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

// A file of such lines, read record by record: comments skipped, malformed lines counted (with
// the last one's line number and reason) and skipped. `Parse` turns one line into a Record.
template <typename Record, LogLineParse (*Parse)(std::string_view, Record&, std::string&)>
class LineLogReader {
 public:
  explicit LineLogReader(const std::string& path) : in_(path) {}
  [[nodiscard]] bool is_open() const { return in_.is_open(); }
  std::optional<Record> next() {
    std::string line;
    while (std::getline(in_, line)) {
      ++line_;
      Record rec;
      std::string error;
      switch (Parse(line, rec, error)) {
        case LogLineParse::kRecord:
          return rec;
        case LogLineParse::kIgnored:
          break;
        case LogLineParse::kMalformed:
          ++malformed_;
          last_error_ = "line " + std::to_string(line_) + ": " + error;
          break;
      }
    }
    return std::nullopt;
  }
  [[nodiscard]] uint64_t malformed() const { return malformed_; }
  [[nodiscard]] const std::string& last_error() const { return last_error_; }
  [[nodiscard]] uint64_t line_number() const { return line_; }

 private:
  std::ifstream in_;
  uint64_t malformed_ = 0;
  uint64_t line_ = 0;
  std::string last_error_;
};

// Writes records as lines with `Format` (microsecond stamps).
template <typename Record, std::string (*Format)(const Record&, bool)>
class LineLogWriter {
 public:
  explicit LineLogWriter(const std::string& path) : out_(path) {}
  [[nodiscard]] bool is_open() const { return out_.is_open(); }
  void write(const Record& rec) { out_ << Format(rec, false) << '\n'; }
  void flush() { out_.flush(); }

 private:
  std::ofstream out_;
};

}  // namespace hal
