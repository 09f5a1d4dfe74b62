#pragma once
// How Amfiprot packets travel: over a serial port as COBS frames (here), or as HID reports
// (hidapi, to come). The device shell only sees packets.
#include <memory>
#include <optional>

#include "amfitrack/amfiprot_codec.hpp"
#include "hal/serial_port.hpp"

namespace amfitrack {

class PacketLink {
 public:
  virtual ~PacketLink() = default;
  virtual std::optional<Packet> receive() = 0;  // non-blocking
  virtual bool send(const Packet& p) = 0;
  [[nodiscard]] virtual bool failed() const = 0;  // device gone (read/write error)
  [[nodiscard]] virtual const CobsStats& framing_stats() const = 0;
};

// COBS-framed packets on a serial port (UART mode, 115200 8N1 by default).
class SerialCobsLink final : public PacketLink {
 public:
  explicit SerialCobsLink(std::unique_ptr<hal::SerialPort> port) : port_(std::move(port)) {}
  std::optional<Packet> receive() override;
  bool send(const Packet& p) override;
  [[nodiscard]] bool failed() const override { return failed_; }
  [[nodiscard]] const CobsStats& framing_stats() const override { return decoder_.stats(); }

 private:
  std::unique_ptr<hal::SerialPort> port_;
  CobsStreamDecoder decoder_;
  bool failed_ = false;
};

}  // namespace amfitrack
