// libFuzzer: candump log lines (files from anywhere: a technician's laptop, a colleague's rig).
#include <cstddef>
#include <cstdint>
#include <string>

#include "hal/can/candump_log.hpp"

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
  return 0;
}
