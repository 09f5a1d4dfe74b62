// libFuzzer: capture log lines (files from anywhere: a technician's laptop, a colleague's rig),
// both kinds: candump CAN lines and the tracker's packet lines.
#include <cstddef>
#include <cstdint>
#include <string>

#include "hal/can/candump_log.hpp"
#include "hal/capture/packet_log.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string line(reinterpret_cast<const char*>(data), size);
  hal::CandumpRecord rec;
  std::string err;
  if (hal::parse_candump_line(line, rec, err) == hal::CandumpParse::kRecord) {
    if (rec.frame.dlc > 8) __builtin_trap();
    // What we parse, we write back; and that parses to the same frame.
    hal::CandumpRecord again;
    if (hal::parse_candump_line(hal::format_candump_line(rec, true), again, err) !=
            hal::CandumpParse::kRecord ||
        !(again.frame == rec.frame)) {
      __builtin_trap();
    }
  }
  hal::PacketRecord pr;
  if (hal::parse_packet_line(line, pr, err) == hal::LogLineParse::kRecord) {
    if (pr.bytes.empty() || pr.bytes.size() > hal::kMaxLoggedPacket) __builtin_trap();
    hal::PacketRecord again;
    if (hal::parse_packet_line(hal::format_packet_line(pr, true), again, err) !=
            hal::LogLineParse::kRecord ||
        again.bytes != pr.bytes || again.sec != pr.sec || again.nsec != pr.nsec) {
      __builtin_trap();
    }
  }
  return 0;
}
