#pragma once
// One interface for every CAN link: SocketCAN, slcan over a serial port, in-process virtual bus.
// Never blocks: send() either queues the frame or says why not; receive() returns what arrived.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "hal/can/can_frame.hpp"

namespace hal {

enum class CanSendResult : uint8_t {
  kOk,
  kQueueFull,  // transmit queue full (ENOBUFS): the frame was dropped and counted
  kBusOff,     // controller is bus-off: nothing can be sent
  kError,      // write failed (errno in the statistics' last error)
  kClosed,
};

enum class CanBusState : uint8_t { kActive, kWarning, kPassive, kBusOff, kClosed };

std::string_view to_string(CanSendResult r);
std::string_view to_string(CanBusState s);

struct CanStats {
  uint64_t frames_in = 0;
  uint64_t frames_out = 0;
  uint64_t tx_dropped = 0;     // send() refused (queue full, bus-off)
  uint64_t rx_dropped = 0;     // received frames lost (overflow, unparsable input)
  uint64_t tx_errors = 0;      // write errors
  uint64_t error_frames = 0;   // controller error frames seen
  uint64_t bus_off_count = 0;  // transitions into bus-off
};

class CanBus {
 public:
  virtual ~CanBus() = default;
  virtual CanSendResult send(const CanFrame& frame) = 0;
  // Next received frame (data or error frame), or nullopt when none is waiting.
  virtual std::optional<StampedCanFrame> receive() = 0;
  [[nodiscard]] virtual CanBusState state() const = 0;
  [[nodiscard]] virtual CanStats stats() const = 0;
  [[nodiscard]] virtual std::string name() const = 0;
};

struct CanOpenResult {
  std::unique_ptr<CanBus> bus;
  std::string error;  // why it could not be opened (bus == nullptr)
};

// Opens "socketcan:<ifname>", "slcan:<serial device>[@baud]" or "virtual:<name>".
// Frames are stamped with `clock` (monotonic) on reception. `receive_ids`: standard ids the
// caller needs; SocketCAN installs them as kernel filters (others: everything is received).
CanOpenResult open_can(std::string_view uri, Clock& clock,
                       const std::vector<uint32_t>& receive_ids = {});

}  // namespace hal
