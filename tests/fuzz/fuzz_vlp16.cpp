// libFuzzer: VLP-16 data and position packets (UDP from anything on the sensor's network) and
// the pcap frame parser (capture files from anywhere).
#include <pcap/pcap.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "hal/capture/pcap_file.hpp"
#include "vlp16/scan_assembler.hpp"
#include "vlp16/vlp16_codec.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::span<const uint8_t> bytes(data, size);
  static vlp16::ScanAssembler assembler{vlp16::ScanConfig{}};
  static int64_t host_ns = 0;
  vlp16::RawDataPacket raw;
  if (vlp16::parse_data_packet(bytes, raw) == vlp16::DecodeError::kNone) {
    std::array<vlp16::Point, vlp16::kReturnsPerPacket> pts;
    const size_t n = vlp16::decode_points(raw, {}, pts);
    if (n > pts.size()) __builtin_trap();
    for (size_t i = 0; i < n; ++i) {
      if (!(pts[i].distance_m <= 131.1f) || pts[i].azimuth >= vlp16::kAzimuthUnits)
        __builtin_trap();
    }
    host_ns += 1'327'000;
    (void)assembler.add(raw, hal::Nanos(host_ns));
    // What parses re-encodes to the same bytes.
    const auto again = vlp16::encode_data_packet(raw);
    for (size_t i = 0; i < again.size(); ++i) {
      if (again[i] != data[i]) __builtin_trap();
    }
  }
  vlp16::PositionPacket pos;
  (void)vlp16::parse_position_packet(bytes, pos);
  hal::PcapUdpPacket udp;
  if (hal::parse_udp_frame(DLT_EN10MB, bytes, udp) == hal::FrameParse::kUdp &&
      udp.payload.size() + 28 > size) {
    __builtin_trap();
  }
  return 0;
}
