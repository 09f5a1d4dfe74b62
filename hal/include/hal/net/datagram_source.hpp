#pragma once
// Where a sensor's datagrams come from: a UDP socket on the robot (hal::UdpReceiver), or an
// in-process queue fed by the simulated world on the simulated clock (hal::DatagramQueue).
// The consumer drains both the same way, so the simulator never bypasses the driver.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>

#include "hal/clock.hpp"

namespace hal {

struct UdpStats {
  uint64_t datagrams = 0;
  uint64_t bytes = 0;
  uint64_t truncated = 0;     // larger than the receive buffer: dropped
  uint64_t kernel_drops = 0;  // socket queue overflowed (SO_RXQ_OVFL; the kernel reports them
                              // with the next datagram it queues), cumulative
  uint64_t errors = 0;        // recvmsg errors other than "nothing to read"
};

struct UdpDatagram {
  std::span<const uint8_t> bytes;
  Nanos stamp{0};            // receive time (monotonic), or the drain time
  uint32_t source_ipv4 = 0;  // host byte order
  uint16_t source_port = 0;
};

class DatagramSource {
 public:
  virtual ~DatagramSource() = default;
  // Hands up to `max_datagrams` datagrams received by `now` to `on` (the span is valid during
  // the call), without blocking; returns how many.
  virtual size_t drain(size_t max_datagrams, Nanos now,
                       const std::function<void(const UdpDatagram&)>& on) = 0;
  [[nodiscard]] virtual UdpStats stats() const = 0;
};

}  // namespace hal
