// libFuzzer: Amfiprot bytes as they could arrive over HID reports or a COBS UART stream.
#include <cstddef>
#include <cstdint>
#include <span>

#include "amfitrack/amfiprot_codec.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::span<const uint8_t> in(data, size);
  const auto p = amfitrack::parse_packet(in);
  if (p.packet) {
    if (p.packet->payload.size() > amfitrack::kMaxPayload) __builtin_trap();
    // Re-encoding a parsed packet gives back exactly the bytes it was parsed from.
    const auto again = amfitrack::encode_packet(*p.packet);
    if (again.size() != p.consumed || !std::equal(again.begin(), again.end(), data))
      __builtin_trap();
    (void)amfitrack::decode_payload(*p.packet);
  }
  (void)amfitrack::parse_hid_report(in);
  amfitrack::CobsStreamDecoder d;
  d.feed(in);
  while (auto pk = d.next())
    (void)amfitrack::decode_payload(*pk);
  return 0;
}
