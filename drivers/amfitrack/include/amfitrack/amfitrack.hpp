#pragma once
// The Amfitrack device shell: drains a PacketLink, picks the configured sensor's 0x1A frames,
// stamps them at reception (time passed in), measures the real rate, counts frame-id gaps
// (drops) and decode errors, feeds the confidence gate, and sends the keep-alive
// (RequestDeviceID broadcast every 2 s, as the vendor SDK does). Bytes are parsed only by the
// codec.
#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>

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
};

struct AmfitrackCounters {
  uint64_t packets = 0;
  uint64_t poses = 0;               // 0x1A from the configured sensor
  uint64_t poses_other_sensor = 0;  // 0x1A from another TX id (ignored)
  uint64_t dropped_frames = 0;      // from frame-id gaps
  std::array<uint64_t, static_cast<size_t>(PayloadError::kCount)> payload_errors{};
  uint64_t keepalives_sent = 0;
  uint64_t send_failures = 0;
};

class Amfitrack {
 public:
  Amfitrack(PacketLink& link, const AmfitrackConfig& config);

  void poll(hal::Nanos now);

  [[nodiscard]] const std::optional<StampedMeasurement>& latest() const { return latest_; }
  [[nodiscard]] GateOutput confidence(hal::Nanos now) const { return gate_.evaluate(now); }
  [[nodiscard]] double rate_hz() const { return rate_hz_; }
  [[nodiscard]] const AmfitrackCounters& counters() const { return counters_; }
  // Devices that answered RequestDeviceID: TX id -> UUID.
  [[nodiscard]] const std::map<uint8_t, DeviceIdReply>& devices() const { return devices_; }
  [[nodiscard]] bool link_failed() const { return link_.failed(); }

 private:
  void on_pose(const SensorMeasurement& m, hal::Nanos stamp);

  PacketLink& link_;
  AmfitrackConfig config_;
  ConfidenceGate gate_;
  AmfitrackCounters counters_;
  std::optional<StampedMeasurement> latest_;
  std::map<uint8_t, DeviceIdReply> devices_;
  double rate_hz_ = 0;
  bool keepalive_sent_ = false;
  hal::Nanos last_keepalive_{0};
  uint8_t packet_number_ = 0;
};

}  // namespace amfitrack
