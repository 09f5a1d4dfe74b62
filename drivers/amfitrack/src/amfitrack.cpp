#include "amfitrack/amfitrack.hpp"

namespace amfitrack {

Amfitrack::Amfitrack(PacketLink& link, const AmfitrackConfig& config)
    : link_(link), config_(config), gate_(config.gate) {}

void Amfitrack::on_pose(const SensorMeasurement& m, hal::Nanos stamp) {
  if (latest_) {
    // 24-bit frame ids: the gap modulo 2^24 counts the frames that never arrived.
    const uint32_t gap = (m.frame_id - latest_->m.frame_id) & 0xFFFFFF;
    if (gap > 1 && gap < 0x800000) counters_.dropped_frames += gap - 1;
    if (stamp > latest_->stamp) {
      // Rate from the reception times, per frame id step (so drops do not read as a slow rate).
      const double hz = 1e9 * (gap > 0 && gap < 0x800000 ? gap : 1) /
                        static_cast<double>((stamp - latest_->stamp).count());
      rate_hz_ = rate_hz_ == 0 ? hz : 0.95 * rate_hz_ + 0.05 * hz;
    }
  }
  gate_.on_frame(m, stamp);
  latest_ = StampedMeasurement{m, stamp};
  ++counters_.poses;
}

void Amfitrack::poll(hal::Nanos now) {
  while (auto p = link_.receive()) {
    ++counters_.packets;
    const ParsedPayload pl = decode_payload(*p);
    if (!pl.payload) {
      ++counters_.payload_errors[static_cast<size_t>(pl.error)];
      continue;
    }
    if (const auto* m = std::get_if<SensorMeasurement>(&*pl.payload)) {
      if (p->header.source == config_.sensor_tx_id) {
        on_pose(*m, now);
      } else {
        ++counters_.poses_other_sensor;
      }
    } else if (const auto* id = std::get_if<DeviceIdReply>(&*pl.payload)) {
      devices_[p->header.source] = *id;
    }
  }
  if (!keepalive_sent_ || now - last_keepalive_ >= config_.keepalive_period) {
    if (link_.send(request_device_id(packet_number_++))) {
      ++counters_.keepalives_sent;
    } else {
      ++counters_.send_failures;
    }
    keepalive_sent_ = true;
    last_keepalive_ = now;
  }
}

}  // namespace amfitrack
