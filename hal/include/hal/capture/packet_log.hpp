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

using PacketLogReader = LineLogReader<PacketRecord, parse_packet_line>;
using PacketLogWriter = LineLogWriter<PacketRecord, format_packet_line>;

}  // namespace hal
