#pragma once
// The Amfitrack device shell: drains a PacketLink, picks the configured sensor's 0x1A frames,
// stamps them at reception (time passed in; the protocol has no device timestamp), measures the
// real rate, counts frame-id gaps (drops) and decode errors, feeds the confidence gate, sends the
// keep-alive (RequestDeviceID broadcast every 2 s, as the vendor SDK does) and asks every device
// that answers for its name and firmware version. Bytes are parsed only by the codec.
#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "amfitrack/confidence_gate.hpp"
#include "amfitrack/packet_link.hpp"

namespace amfitrack {

struct AmfitrackConfig {
  uint8_t sensor_tx_id = 2;  // the worn sensor (frames come through the source's link)
  GateConfig gate;
  hal::Nanos keepalive_period = std::chrono::seconds(2);
};

struct StampedMeasurement {
  SensorMeasurement m;
  hal::Nanos stamp;
  Confidence confidence = Confidence::kBad;  // the gate's verdict right after this frame
};

// A device that answered RequestDeviceID (and, later, the name / firmware requests).
struct DeviceInfo {
  uint8_t tx_id = 0;
  std::array<uint32_t, 3> uuid{};
  std::string name;      // empty until answered
  std::string firmware;  // "w0.w1.w2.w3" (the four words as sent), empty until answered
  hal::Nanos last_seen{0};
};

struct AmfitrackCounters {
  uint64_t packets = 0;
  uint64_t poses = 0;               // 0x1A from the configured sensor
  uint64_t poses_other_sensor = 0;  // 0x1A from another TX id (ignored)
  uint64_t dropped_frames = 0;      // from frame-id gaps
  uint64_t repeated_frames = 0;     // same frame id again (or a jump backwards)
  std::array<uint64_t, static_cast<size_t>(PayloadError::kCount)> payload_errors{};
  uint64_t keepalives_sent = 0;
  uint64_t send_failures = 0;
};

class Amfitrack {
 public:
  // Frames drained in one poll are kept for the caller (e.g. every one feeds the estimator).
  static constexpr size_t kMaxFramesPerPoll = 64;

  Amfitrack(PacketLink& link, const AmfitrackConfig& config);

  void poll(hal::Nanos now);

  // The configured sensor's frames received in the latest poll (oldest first).
  [[nodiscard]] const std::vector<StampedMeasurement>& new_measurements() const { return fresh_; }
  [[nodiscard]] const std::optional<StampedMeasurement>& latest() const { return latest_; }
  [[nodiscard]] GateOutput confidence(hal::Nanos now) const { return gate_.evaluate(now); }
  // Frames per second of the sensor (frame-id steps, so drops do not read as a slow rate),
  // measured over windows of at least kRateWindow of polls; 0 until the first window closes.
  [[nodiscard]] double rate_hz() const { return rate_hz_; }
  static constexpr hal::Nanos kRateWindow = std::chrono::milliseconds(500);
  [[nodiscard]] const AmfitrackCounters& counters() const { return counters_; }
  [[nodiscard]] const std::map<uint8_t, DeviceInfo>& devices() const { return devices_; }
  [[nodiscard]] bool link_failed() const { return link_.failed(); }

 private:
  void on_pose(const SensorMeasurement& m, hal::Nanos stamp);
  void on_reply(const Packet& p, const Payload& payload, hal::Nanos now);
  bool send(const Packet& p);

  PacketLink& link_;
  AmfitrackConfig config_;
  ConfidenceGate gate_;
  AmfitrackCounters counters_;
  std::vector<StampedMeasurement> fresh_;
  std::optional<StampedMeasurement> latest_;
  std::map<uint8_t, DeviceInfo> devices_;
  double rate_hz_ = 0;
  bool rate_window_open_ = false;
  uint32_t rate_window_ids_ = 0;  // frame-id steps since the window opened
  hal::Nanos rate_window_start_{0};
  bool keepalive_sent_ = false;
  hal::Nanos last_keepalive_{0};
  uint8_t packet_number_ = 0;
};

std::string firmware_text(const FirmwareVersionReply& r);

}  // namespace amfitrack
