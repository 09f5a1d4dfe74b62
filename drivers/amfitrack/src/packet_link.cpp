#include "amfitrack/packet_link.hpp"

#include <array>

namespace amfitrack {

std::optional<Packet> SerialCobsLink::receive() {
  if (auto p = decoder_.next()) return p;
  if (failed_) return std::nullopt;
  std::array<uint8_t, 1024> buf{};
  for (int reads = 0; reads < 8; ++reads) {  // bounded: a flooding device cannot stall the task
    const long n = port_->read(buf.data(), buf.size());
    if (n < 0) {
      failed_ = true;
      break;
    }
    if (n == 0) break;
    decoder_.feed(std::span<const uint8_t>(buf.data(), static_cast<size_t>(n)));
    if (static_cast<size_t>(n) < buf.size()) break;
  }
  return decoder_.next();
}

bool SerialCobsLink::send(const Packet& p) {
  if (failed_) return false;
  std::vector<uint8_t> frame = cobs_encode(encode_packet(p));
  frame.push_back(0);
  const long n = port_->write(frame.data(), frame.size());
  if (n < 0) failed_ = true;
  return n == static_cast<long>(frame.size());
}

}  // namespace amfitrack
