#include "hal/capture/pcap_file.hpp"

#include <pcap/pcap.h>

#include <array>

namespace hal {
namespace {

uint16_t be16(const uint8_t* p) {
  return static_cast<uint16_t>(p[0] << 8 | p[1]);
}
uint32_t be32(const uint8_t* p) {
  return static_cast<uint32_t>(p[0]) << 24 | static_cast<uint32_t>(p[1]) << 16 |
         static_cast<uint32_t>(p[2]) << 8 | p[3];
}
void put16(std::vector<uint8_t>& v, uint16_t x) {
  v.push_back(static_cast<uint8_t>(x >> 8));
  v.push_back(static_cast<uint8_t>(x));
}
void put32(std::vector<uint8_t>& v, uint32_t x) {
  put16(v, static_cast<uint16_t>(x >> 16));
  put16(v, static_cast<uint16_t>(x));
}

constexpr uint16_t kEtherIpv4 = 0x0800;
constexpr uint16_t kEtherVlan = 0x8100;
constexpr uint8_t kProtoUdp = 17;

}  // namespace

FrameParse parse_udp_frame(int link_type, std::span<const uint8_t> f, PcapUdpPacket& out) {
  size_t off = 0;
  uint16_t ether_type = 0;
  if (link_type == DLT_EN10MB) {
    if (f.size() < 14) return FrameParse::kMalformed;
    ether_type = be16(&f[12]);
    off = 14;
    if (ether_type == kEtherVlan) {
      if (f.size() < 18) return FrameParse::kMalformed;
      ether_type = be16(&f[16]);
      off = 18;
    }
  } else if (link_type == DLT_LINUX_SLL) {
    if (f.size() < 16) return FrameParse::kMalformed;
    ether_type = be16(&f[14]);
    off = 16;
  } else if (link_type == DLT_RAW) {
    ether_type = kEtherIpv4;
  } else {
    return FrameParse::kNotUdp;
  }
  if (ether_type != kEtherIpv4) return FrameParse::kNotUdp;
  if (f.size() < off + 20) return FrameParse::kMalformed;
  const uint8_t* ip = &f[off];
  if ((ip[0] >> 4) != 4) return FrameParse::kMalformed;
  const size_t ihl = static_cast<size_t>(ip[0] & 0x0F) * 4;
  const size_t total = be16(&ip[2]);
  const size_t available = f.size() - off;
  if (ihl < 20 || ihl > available) return FrameParse::kMalformed;
  if (ip[9] != kProtoUdp) return FrameParse::kNotUdp;
  const uint16_t frag = be16(&ip[6]);
  if ((frag & 0x3FFF) != 0) return FrameParse::kFragment;  // MF set or an offset
  if (ihl + 8 > available) return FrameParse::kMalformed;
  const uint8_t* udp = ip + ihl;
  const size_t udp_len = be16(&udp[4]);
  // The UDP length is the authority, within the captured bytes. The IPv4 total length may be
  // larger: VLP-16 position packets claim 1234 bytes for a 512-byte payload (seen in real
  // captures), so only a total SHORTER than the UDP datagram is inconsistent.
  if (udp_len < 8 || ihl + udp_len > available || total < ihl + udp_len) {
    return FrameParse::kMalformed;
  }
  out.source_ipv4 = be32(&ip[12]);
  out.destination_ipv4 = be32(&ip[16]);
  out.source_port = be16(&udp[0]);
  out.destination_port = be16(&udp[2]);
  out.payload.assign(udp + 8, udp + udp_len);
  return FrameParse::kUdp;
}

std::unique_ptr<PcapReader> PcapReader::open(const std::string& path, std::string& error) {
  std::array<char, PCAP_ERRBUF_SIZE> err{};
  ::pcap* h =
      pcap_open_offline_with_tstamp_precision(path.c_str(), PCAP_TSTAMP_PRECISION_NANO, err.data());
  if (h == nullptr) {
    error = "pcap: " + path + ": " + err.data();
    return nullptr;
  }
  return std::unique_ptr<PcapReader>(new PcapReader(h, pcap_datalink(h)));
}

PcapReader::~PcapReader() {
  pcap_close(handle_);
}

std::optional<PcapUdpPacket> PcapReader::next(uint16_t port) {
  pcap_pkthdr* hdr = nullptr;
  const u_char* data = nullptr;
  while (pcap_next_ex(handle_, &hdr, &data) == 1) {
    ++stats_.frames;
    PcapUdpPacket p;
    switch (parse_udp_frame(link_type_, std::span<const uint8_t>(data, hdr->caplen), p)) {
      case FrameParse::kUdp:
        if (port != 0 && p.destination_port != port) {
          ++stats_.other_port;
          continue;
        }
        ++stats_.udp;
        p.capture_time = Nanos(static_cast<int64_t>(hdr->ts.tv_sec) * 1'000'000'000 +
                               static_cast<int64_t>(hdr->ts.tv_usec));  // nanoseconds (NANO)
        return p;
      case FrameParse::kNotUdp:
        ++stats_.not_udp;
        break;
      case FrameParse::kFragment:
        ++stats_.fragments;
        break;
      case FrameParse::kMalformed:
        ++stats_.malformed;
        break;
    }
  }
  return std::nullopt;
}

std::vector<uint8_t> build_udp_frame(const PcapUdpPacket& p) {
  std::vector<uint8_t> f;
  f.reserve(42 + p.payload.size());
  // Ethernet: broadcast from a locally administered address.
  for (int i = 0; i < 6; ++i)
    f.push_back(0xFF);
  const std::array<uint8_t, 6> source_mac = {0x02, 0x00, 0x00, 0x00, 0x00, 0x01};
  f.insert(f.end(), source_mac.begin(), source_mac.end());
  put16(f, kEtherIpv4);
  // IPv4 header, 20 bytes.
  const size_t ip_start = f.size();
  const auto total = static_cast<uint16_t>(20 + 8 + p.payload.size());
  f.push_back(0x45);
  f.push_back(0x00);
  put16(f, total);
  put16(f, 0);       // identification
  put16(f, 0x4000);  // don't fragment
  f.push_back(64);   // TTL
  f.push_back(kProtoUdp);
  put16(f, 0);  // checksum, below
  put32(f, p.source_ipv4);
  put32(f, p.destination_ipv4);
  uint32_t sum = 0;
  for (size_t i = ip_start; i < ip_start + 20; i += 2)
    sum += be16(&f[i]);
  while ((sum >> 16) != 0)
    sum = (sum & 0xFFFF) + (sum >> 16);
  const auto checksum = static_cast<uint16_t>(~sum);
  f[ip_start + 10] = static_cast<uint8_t>(checksum >> 8);
  f[ip_start + 11] = static_cast<uint8_t>(checksum);
  // UDP header; checksum 0 = not computed (allowed for IPv4).
  put16(f, p.source_port);
  put16(f, p.destination_port);
  put16(f, static_cast<uint16_t>(8 + p.payload.size()));
  put16(f, 0);
  f.insert(f.end(), p.payload.begin(), p.payload.end());
  return f;
}

std::unique_ptr<PcapWriter> PcapWriter::open(const std::string& path, std::string& error) {
  ::pcap* dead =
      pcap_open_dead_with_tstamp_precision(DLT_EN10MB, 65535, PCAP_TSTAMP_PRECISION_MICRO);
  if (dead == nullptr) {
    error = "pcap: cannot create a handle";
    return nullptr;
  }
  ::pcap_dumper* d = pcap_dump_open(dead, path.c_str());
  if (d == nullptr) {
    error = "pcap: " + path + ": " + pcap_geterr(dead);
    pcap_close(dead);
    return nullptr;
  }
  return std::unique_ptr<PcapWriter>(new PcapWriter(dead, d));
}

PcapWriter::~PcapWriter() {
  pcap_dump_close(dumper_);
  pcap_close(dead_);
}

void PcapWriter::write(const PcapUdpPacket& packet) {
  const std::vector<uint8_t> frame = build_udp_frame(packet);
  pcap_pkthdr hdr{};
  const int64_t ns = packet.capture_time.count();
  hdr.ts.tv_sec = static_cast<time_t>(ns / 1'000'000'000);
  hdr.ts.tv_usec = static_cast<suseconds_t>((ns % 1'000'000'000) / 1000);
  hdr.caplen = static_cast<bpf_u_int32>(frame.size());
  hdr.len = hdr.caplen;
  pcap_dump(reinterpret_cast<u_char*>(dumper_), &hdr, frame.data());
}

void PcapWriter::flush() {
  (void)pcap_dump_flush(dumper_);
}

}  // namespace hal
