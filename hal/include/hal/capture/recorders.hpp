#pragma once
// Taps that record a device's traffic while passing it through unchanged, into the capture
// formats other tools read (DESIGN.md section 7): CAN as a candump log (both directions, as
// `candump -l` shows them), UDP datagrams as pcap (Wireshark, VeloView). Times are wall-clock
// (monotonic stamps shifted by the offset measured when the tap was made), as those tools expect.
#include <memory>
#include <string>

#include "hal/can/can_bus.hpp"
#include "hal/can/candump_log.hpp"
#include "hal/capture/pcap_file.hpp"
#include "hal/net/datagram_source.hpp"

namespace hal {

// Wall-clock time of a monotonic stamp (offset taken once, at construction).
class WallClockOffset {
 public:
  WallClockOffset();
  [[nodiscard]] Nanos to_wall(Nanos monotonic) const { return monotonic + offset_; }

 private:
  Nanos offset_{0};
};

class RecordingCanBus final : public CanBus {
 public:
  RecordingCanBus(std::unique_ptr<CanBus> inner, const std::string& path, std::string iface,
                  Clock& clock);
  CanSendResult send(const CanFrame& frame) override;
  std::optional<StampedCanFrame> receive() override;
  [[nodiscard]] CanBusState state() const override { return inner_->state(); }
  [[nodiscard]] CanStats stats() const override { return inner_->stats(); }
  [[nodiscard]] std::string name() const override { return inner_->name(); }
  [[nodiscard]] bool ok() const { return writer_.is_open(); }

 private:
  void log(const CanFrame& frame, Nanos monotonic);
  std::unique_ptr<CanBus> inner_;
  CandumpWriter writer_;
  std::string iface_;
  Clock& clock_;
  WallClockOffset wall_;
};

class RecordingDatagramSource final : public DatagramSource {
 public:
  // `to_port`: the destination port written into the frames (2368 for VLP-16 data).
  RecordingDatagramSource(std::unique_ptr<DatagramSource> inner, std::unique_ptr<PcapWriter> out,
                          uint16_t to_port);
  size_t drain(size_t max_datagrams, Nanos now,
               const std::function<void(const UdpDatagram&)>& on) override;
  [[nodiscard]] UdpStats stats() const override { return inner_->stats(); }

 private:
  std::unique_ptr<DatagramSource> inner_;
  std::unique_ptr<PcapWriter> out_;
  uint16_t to_port_;
  WallClockOffset wall_;
  PcapUdpPacket scratch_;
};

}  // namespace hal
