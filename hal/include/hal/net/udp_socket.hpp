#pragma once
// UDP for sensor streams (VLP-16 data on 2368, position on 8308): a receiver bound to an address
// and port with a large kernel buffer, drained without blocking, with kernel receive timestamps
// (shifted to the monotonic clock) and the kernel's own drop counter (SO_RXQ_OVFL); and a small
// sender for simulators and tests.
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "hal/clock.hpp"
#include "hal/net/datagram_source.hpp"

namespace hal {

struct UdpEndpoint {
  std::string address = "0.0.0.0";  // IPv4 dotted quad; 0.0.0.0 = any
  uint16_t port = 0;
};
// "udp:<addr>:<port>" or "<addr>:<port>"; nullopt-like: returns false and says why.
bool parse_udp_endpoint(const std::string& text, UdpEndpoint& out, std::string& error);

// How a datagram is stamped: by the kernel at arrival (SO_TIMESTAMPNS, aged back from the drain's
// `now`: the real daemon), or with the drain's `now` (a simulated clock: the wall time a datagram
// waited in the kernel means nothing there, and on a loaded machine it aged scans into
// staleness).
enum class UdpStamp { kKernel, kDrain };

class UdpReceiver final : public DatagramSource {
 public:
  struct OpenResult {
    std::unique_ptr<UdpReceiver> receiver;
    std::string error;
  };
  // `receive_buffer_bytes`: SO_RCVBUF asked for (the kernel may cap it: see buffer_bytes()).
  static OpenResult open(const UdpEndpoint& endpoint, int receive_buffer_bytes = 4 << 20,
                         UdpStamp stamp = UdpStamp::kKernel);
  ~UdpReceiver() override;
  UdpReceiver(const UdpReceiver&) = delete;
  UdpReceiver& operator=(const UdpReceiver&) = delete;

  // Reads up to `max_datagrams` queued datagrams without blocking and hands each to `on`
  // (the span is valid during the call). `now` is the monotonic time of this drain.
  size_t drain(size_t max_datagrams, Nanos now,
               const std::function<void(const UdpDatagram&)>& on) override;

  [[nodiscard]] UdpStats stats() const override { return stats_; }
  [[nodiscard]] uint16_t port() const { return port_; }  // the bound port (for port 0)
  [[nodiscard]] int buffer_bytes() const { return buffer_bytes_; }
  [[nodiscard]] int fd() const { return fd_; }

 private:
  UdpReceiver(int fd, uint16_t port, int buffer_bytes);
  int fd_;
  uint16_t port_;
  int buffer_bytes_;
  uint32_t last_ovfl_ = 0;
  UdpStats stats_;
  std::vector<uint8_t> buffer_;
};

class UdpSender {
 public:
  static std::unique_ptr<UdpSender> open(std::string& error);
  ~UdpSender();
  UdpSender(const UdpSender&) = delete;
  UdpSender& operator=(const UdpSender&) = delete;
  bool send_to(const UdpEndpoint& to, std::span<const uint8_t> bytes);

 private:
  explicit UdpSender(int fd) : fd_(fd) {}
  int fd_;
};

}  // namespace hal
