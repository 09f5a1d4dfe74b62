#include "firmware/capture_recorder.hpp"

#include <fmt/format.h>

#include <chrono>
#include <filesystem>
#include <fstream>

#include "amfitrack/amfiprot_codec.hpp"
#include "amfitrack/tap_link.hpp"

namespace firmware {

std::unique_ptr<CaptureRecorder> CaptureRecorder::open(const std::string& dir,
                                                       const DaemonConfig& cfg,
                                                       const std::string& note,
                                                       std::string& error) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) {
    error = fmt::format("--record {}: cannot create: {}", dir, ec.message());
    return nullptr;
  }
  std::ofstream meta(dir + "/capture.yaml");
  const auto now = std::chrono::system_clock::now().time_since_epoch();
  meta << "# companiond capture (DESIGN.md section 7)\n"
       << fmt::format("created_unix_s: {:.3f}\n", std::chrono::duration<double>(now).count())
       << "files:\n"
       << "  base: base.candump      # candump -l format, interface can0\n"
       << "  tracker: tracker.log    # (sec.usec) amfi0 <hex of one Amfiprot packet>\n"
       << "  lidar: lidar.pcap       # Ethernet/IPv4/UDP to port 2368\n"
       << "devices:\n"
       << fmt::format("  tracker: \"{}\"\n  lidar: \"{}\"\n  base: \"{}\"\n", cfg.devices.tracker,
                      cfg.devices.lidar, cfg.devices.base)
       << fmt::format("tracker_sensor_tx_id: {}\n", cfg.tracker.sensor_tx_id)
       << fmt::format("note: \"{}\"\n", note);
  if (!meta) {
    error = fmt::format("--record {}: cannot write capture.yaml", dir);
    return nullptr;
  }
  return std::unique_ptr<CaptureRecorder>(new CaptureRecorder(dir));
}

std::unique_ptr<hal::CanBus> CaptureRecorder::wrap_base(std::unique_ptr<hal::CanBus> bus,
                                                        hal::Clock& clock) {
  return std::make_unique<hal::RecordingCanBus>(std::move(bus), dir_ + "/base.candump", "can0",
                                                clock);
}

std::unique_ptr<amfitrack::PacketLink> CaptureRecorder::wrap_tracker(
    std::unique_ptr<amfitrack::PacketLink> link, hal::Clock& clock) {
  auto writer = std::make_shared<hal::PacketLogWriter>(dir_ + "/tracker.log");
  auto wall = std::make_shared<hal::WallClockOffset>();
  return std::make_unique<amfitrack::TapLink>(
      std::move(link), [writer, wall, &clock](const amfitrack::Packet& p) {
        const int64_t t = wall->to_wall(clock.now()).count();
        writer->write(hal::PacketRecord{t / 1'000'000'000, t % 1'000'000'000, "amfi0",
                                        amfitrack::encode_packet(p)});
      });
}

std::unique_ptr<hal::DatagramSource> CaptureRecorder::wrap_lidar(
    std::unique_ptr<hal::DatagramSource> source, std::string& error) {
  auto out = hal::PcapWriter::open(dir_ + "/lidar.pcap", error);
  if (!out) return source;  // keep running unrecorded; the caller logs `error`
  return std::make_unique<hal::RecordingDatagramSource>(std::move(source), std::move(out), 2368);
}

}  // namespace firmware
