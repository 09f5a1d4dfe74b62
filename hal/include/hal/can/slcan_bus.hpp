#pragma once
// CAN over an slcan (Lawicel) USB adapter on a serial port. Opening sends `C` (close, in case it
// was left open), `S<n>` (bit rate) and `O` (open) without waiting for replies: many adapters
// never acknowledge. Replies and errors that do arrive are counted.
#include <memory>

#include "hal/can/can_bus.hpp"
#include "hal/can/slcan_codec.hpp"
#include "hal/serial_port.hpp"

namespace hal {

class SlcanBus final : public CanBus {
 public:
  // `bitrate_kbps`: 500 for the Scout Mini.
  static CanOpenResult open(const std::string& device, int baud, int bitrate_kbps, Clock& clock);

  CanSendResult send(const CanFrame& frame) override;
  std::optional<StampedCanFrame> receive() override;
  [[nodiscard]] CanBusState state() const override;
  [[nodiscard]] CanStats stats() const override;
  [[nodiscard]] std::string name() const override { return "slcan:" + device_; }
  [[nodiscard]] const slcan::ParserStats& parser_stats() const { return parser_.stats(); }

  SlcanBus(std::unique_ptr<SerialPort> port, std::string device, Clock& clock);

 private:
  bool write_all(const std::string& text);
  void pump();

  std::unique_ptr<SerialPort> port_;
  std::string device_;
  Clock& clock_;
  slcan::Parser parser_;
  std::string tx_backlog_;  // bytes the port did not take yet
  CanStats stats_;
  bool failed_ = false;
};

}  // namespace hal
