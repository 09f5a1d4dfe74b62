#pragma once
// pcap captures of UDP sensor streams (the VLP-16's), read and written with libpcap so the files
// open in Wireshark and VeloView and theirs replay here. Frames: Ethernet II (optionally one
// 802.1Q tag) or Linux cooked capture (`tcpdump -i any`), IPv4, UDP. Anything else is counted
// and skipped; fragments are counted (a VLP-16 never fragments).
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "hal/clock.hpp"

struct pcap;
struct pcap_dumper;

namespace hal {

struct PcapUdpPacket {
  Nanos capture_time{0};  // since the Unix epoch, as recorded
  uint32_t source_ipv4 = 0;
  uint32_t destination_ipv4 = 0;
  uint16_t source_port = 0;
  uint16_t destination_port = 0;
  std::vector<uint8_t> payload;
};

struct PcapStats {
  uint64_t frames = 0;
  uint64_t udp = 0;         // returned
  uint64_t other_port = 0;  // UDP, filtered out by port
  uint64_t not_udp = 0;     // ARP, TCP, IPv6 ...
  uint64_t fragments = 0;
  uint64_t malformed = 0;  // truncated or inconsistent headers
};

class PcapReader {
 public:
  static std::unique_ptr<PcapReader> open(const std::string& path, std::string& error);
  ~PcapReader();
  PcapReader(const PcapReader&) = delete;
  PcapReader& operator=(const PcapReader&) = delete;

  // Next UDP packet to `port` (any port when 0); nullopt at the end of the file.
  std::optional<PcapUdpPacket> next(uint16_t port = 0);
  [[nodiscard]] const PcapStats& stats() const { return stats_; }
  [[nodiscard]] int link_type() const { return link_type_; }

 private:
  PcapReader(::pcap* handle, int link_type) : handle_(handle), link_type_(link_type) {}
  ::pcap* handle_;
  int link_type_;
  PcapStats stats_;
};

// Parses one captured frame of `link_type` (DLT_*). Pure; exposed for tests and fuzzing.
enum class FrameParse : uint8_t { kUdp, kNotUdp, kFragment, kMalformed };
FrameParse parse_udp_frame(int link_type, std::span<const uint8_t> frame, PcapUdpPacket& out);

// Writes Ethernet/IPv4/UDP frames (microsecond classic pcap, the most widely read format).
class PcapWriter {
 public:
  static std::unique_ptr<PcapWriter> open(const std::string& path, std::string& error);
  ~PcapWriter();
  PcapWriter(const PcapWriter&) = delete;
  PcapWriter& operator=(const PcapWriter&) = delete;
  void write(const PcapUdpPacket& packet);
  void flush();

 private:
  PcapWriter(::pcap* dead, ::pcap_dumper* dumper) : dead_(dead), dumper_(dumper) {}
  ::pcap* dead_;
  ::pcap_dumper* dumper_;
};

// The Ethernet/IPv4/UDP frame the writer records (IPv4 header checksum set, UDP checksum 0).
std::vector<uint8_t> build_udp_frame(const PcapUdpPacket& packet);

}  // namespace hal
