#include "hal/capture/packet_log.hpp"

#include "hal/can/hex.hpp"

namespace hal {

LogLineParse parse_packet_line(std::string_view line, PacketRecord& out, std::string& error) {
  LogLine ll;
  const LogLineParse r = split_log_line(line, ll, error);
  if (r != LogLineParse::kRecord) return r;
  if (ll.payload.empty()) {
    error = "no packet bytes";
    return LogLineParse::kMalformed;
  }
  if (ll.payload.size() % 2 != 0) {
    error = "odd number of hex digits";
    return LogLineParse::kMalformed;
  }
  if (ll.payload.size() / 2 > kMaxLoggedPacket) {
    error = "packet longer than 4096 bytes";
    return LogLineParse::kMalformed;
  }
  std::vector<uint8_t> bytes(ll.payload.size() / 2);
  for (size_t i = 0; i < bytes.size(); ++i) {
    const int hi = hex::digit_value(ll.payload[2 * i]);
    const int lo = hex::digit_value(ll.payload[2 * i + 1]);
    if (hi < 0 || lo < 0) {
      error = "bad hex digit";
      return LogLineParse::kMalformed;
    }
    bytes[i] = static_cast<uint8_t>(hi * 16 + lo);
  }
  out.sec = ll.sec;
  out.nsec = ll.nsec;
  out.iface = std::string(ll.iface);
  out.bytes = std::move(bytes);
  return LogLineParse::kRecord;
}

std::string format_packet_line(const PacketRecord& rec, bool nine_digits) {
  std::string line = log_line_prefix(rec.sec, rec.nsec, rec.iface, nine_digits);
  hex::append_bytes(line, rec.bytes.data(), rec.bytes.size());
  return line;
}

}  // namespace hal
