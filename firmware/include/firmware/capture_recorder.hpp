#pragma once
// `companiond --record DIR`: a capture directory of everything the devices said, in formats
// other tools read (DESIGN.md section 7):
//   base.candump   the Scout Mini's CAN traffic, both directions (candump -l; canplayer)
//   tracker.log    Amfitrack packets received, `(sec.usec) amfi0 <hex>` (companion-tracker decode)
//   lidar.pcap     VLP-16 data packets (Wireshark, VeloView; companion-lidar decode)
//   capture.yaml   what was recorded, when, from which devices
// The device ends are wrapped before they are attached to the daemon; traffic passes unchanged.
#include <memory>
#include <string>

#include "amfitrack/packet_link.hpp"
#include "firmware/config/daemon_config.hpp"
#include "hal/can/can_bus.hpp"
#include "hal/capture/packet_log.hpp"
#include "hal/capture/recorders.hpp"
#include "hal/net/datagram_source.hpp"

namespace firmware {

class CaptureRecorder {
 public:
  // Creates `dir` and writes capture.yaml; nullptr and `error` when it cannot.
  static std::unique_ptr<CaptureRecorder> open(const std::string& dir, const DaemonConfig& cfg,
                                               const std::string& note, std::string& error);

  std::unique_ptr<hal::CanBus> wrap_base(std::unique_ptr<hal::CanBus> bus, hal::Clock& clock);
  std::unique_ptr<amfitrack::PacketLink> wrap_tracker(std::unique_ptr<amfitrack::PacketLink> link,
                                                      hal::Clock& clock);
  std::unique_ptr<hal::DatagramSource> wrap_lidar(std::unique_ptr<hal::DatagramSource> source,
                                                  std::string& error);
  [[nodiscard]] const std::string& dir() const { return dir_; }

 private:
  explicit CaptureRecorder(std::string dir) : dir_(std::move(dir)) {}
  std::string dir_;
};

}  // namespace firmware
