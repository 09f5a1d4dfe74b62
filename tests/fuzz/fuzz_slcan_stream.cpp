// libFuzzer: bytes from a USB-CAN adapter in slcan mode (noise, resets, wrong baud rates).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "hal/can/slcan_codec.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  hal::slcan::Parser parser;
  // Feed in two pieces, as reads split the stream anywhere.
  const size_t cut = size > 0 ? data[0] % (size + 1) : 0;
  parser.feed(std::string_view(reinterpret_cast<const char*>(data), cut));
  parser.feed(std::string_view(reinterpret_cast<const char*>(data) + cut, size - cut));
  while (auto f = parser.next_frame()) {
    if (f->dlc > 8 || f->error) __builtin_trap();
    if (f->extended ? f->id > 0x1FFFFFFF : f->id > 0x7FF) __builtin_trap();
    // Re-encoding a decoded frame always works and decodes to the same frame.
    const auto text = hal::slcan::encode(*f);
    if (!text) __builtin_trap();
    hal::slcan::Parser again;
    again.feed(*text);
    const auto back = again.next_frame();
    if (!back || !(*back == *f)) __builtin_trap();
  }
  return 0;
}
