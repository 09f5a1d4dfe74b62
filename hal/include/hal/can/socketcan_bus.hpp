#pragma once
// Linux SocketCAN (CAN_RAW): receive filters on the ids the driver needs, error frames enabled
// (TX timeout, controller, ACK, bus-off, restarted; not bus errors, which flood), kernel receive
// timestamps, non-blocking writes where a full queue (ENOBUFS) drops the stale frame and counts.
#include <linux/can.h>

#include <string>
#include <vector>

#include "hal/can/can_bus.hpp"

namespace hal::socketcan {

// Pure helpers (unit-tested without a CAN socket).
can_frame to_linux(const CanFrame& f);
CanFrame from_linux(const can_frame& f);
// One exact-match filter per standard id (empty -> receive everything).
std::vector<can_filter> make_filters(const std::vector<uint32_t>& standard_ids);
// The error classes we subscribe to.
can_err_mask_t error_mask();

struct ErrorFrameInfo {
  bool tx_timeout = false;
  bool lost_arbitration = false;
  bool controller = false;
  bool rx_overflow = false;
  bool warning = false;  // controller error counters reached the warning level
  bool passive = false;  // error-passive
  bool ack = false;      // no acknowledgement: nothing else on the bus (base off / unplugged)
  bool bus_off = false;
  bool restarted = false;
  std::string text;  // e.g. "bus-off", "no ACK (nothing on the bus?)"
};
ErrorFrameInfo decode_error_frame(const CanFrame& f);

}  // namespace hal::socketcan

namespace hal {

class SocketCanBus final : public CanBus {
 public:
  static CanOpenResult open(const std::string& ifname, const std::vector<uint32_t>& filter_ids,
                            Clock& clock);
  ~SocketCanBus() override;

  CanSendResult send(const CanFrame& frame) override;
  std::optional<StampedCanFrame> receive() override;
  [[nodiscard]] CanBusState state() const override { return state_; }
  [[nodiscard]] CanStats stats() const override { return stats_; }
  [[nodiscard]] std::string name() const override { return "socketcan:" + ifname_; }

  SocketCanBus(int fd, std::string ifname, Clock& clock);

 private:
  int fd_;
  std::string ifname_;
  Clock& clock_;
  CanBusState state_ = CanBusState::kActive;
  CanStats stats_;
};

}  // namespace hal
