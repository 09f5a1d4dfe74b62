#pragma once
// Packet captures of byte-oriented devices as candump-style text (DESIGN.md section 7):
//   (1699999999.123456) amfi0 3400071A0200...
// one packet per line, its bytes as hex (either case on input, upper case on output).
#include <cstdint>
#include <fstream>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "hal/capture/log_line.hpp"

namespace hal {

inline constexpr size_t kMaxLoggedPacket = 4096;

struct PacketRecord {
  int64_t sec = 0;
  int64_t nsec = 0;
  std::string iface;
  std::vector<uint8_t> bytes;
};

LogLineParse parse_packet_line(std::string_view line, PacketRecord& out, std::string& error);
std::string format_packet_line(const PacketRecord& rec, bool nine_digits = false);

class PacketLogReader {
 public:
  explicit PacketLogReader(const std::string& path);
  [[nodiscard]] bool is_open() const { return in_.is_open(); }
  // Next record; malformed lines are counted and skipped.
  std::optional<PacketRecord> next();
  [[nodiscard]] uint64_t malformed() const { return malformed_; }
  [[nodiscard]] const std::string& last_error() const { return last_error_; }
  [[nodiscard]] uint64_t line_number() const { return line_; }

 private:
  std::ifstream in_;
  uint64_t malformed_ = 0;
  uint64_t line_ = 0;
  std::string last_error_;
};

class PacketLogWriter {
 public:
  explicit PacketLogWriter(const std::string& path);
  [[nodiscard]] bool is_open() const { return out_.is_open(); }
  void write(const PacketRecord& rec);
  void flush() { out_.flush(); }

 private:
  std::ofstream out_;
};

}  // namespace hal
