#include "amfitrack/amfitrack.hpp"

#include <fmt/format.h>

namespace amfitrack {

std::string firmware_text(const FirmwareVersionReply& r) {
  return fmt::format("{}.{}.{}.{}", r.words[0], r.words[1], r.words[2], r.words[3]);
}

Amfitrack::Amfitrack(PacketLink& link, const AmfitrackConfig& config)
    : link_(link), config_(config), gate_(config.gate) {
  fresh_.reserve(kMaxFramesPerPoll);
}

bool Amfitrack::send(const Packet& p) {
  const bool ok = link_.send(p);
  if (!ok) ++counters_.send_failures;
  return ok;
}

void Amfitrack::on_pose(const SensorMeasurement& m, hal::Nanos stamp) {
  if (latest_) {
    // 24-bit frame ids: the gap modulo 2^24 counts the frames that never arrived.
    const uint32_t gap = (m.frame_id - latest_->m.frame_id) & 0xFFFFFF;
    const bool forward = gap > 0 && gap < 0x800000;
    if (!forward) ++counters_.repeated_frames;
    if (forward && gap > 1) counters_.dropped_frames += gap - 1;
    if (forward) rate_window_ids_ += gap;
  }
  gate_.on_frame(m, stamp);
  latest_ = StampedMeasurement{m, stamp, gate_.evaluate(stamp).confidence};
  if (fresh_.size() < kMaxFramesPerPoll) fresh_.push_back(*latest_);
  ++counters_.poses;
}

void Amfitrack::on_reply(const Packet& p, const Payload& payload, hal::Nanos now) {
  const uint8_t tx = p.header.source;
  if (const auto* id = std::get_if<DeviceIdReply>(&payload)) {
    const bool is_new = devices_.find(tx) == devices_.end();
    DeviceInfo& d = devices_[tx];
    d.tx_id = tx;
    d.uuid = id->uuid;
    d.last_seen = now;
    if (is_new) {
      // Discovery: ask a new device who it is (answers arrive in later polls).
      send(request_device_name(packet_number_++, tx));
      send(request_firmware_version(packet_number_++, tx));
    }
    return;
  }
  auto it = devices_.find(tx);
  if (it == devices_.end()) return;
  if (const auto* n = std::get_if<DeviceNameReply>(&payload)) it->second.name = n->name;
  if (const auto* f = std::get_if<FirmwareVersionReply>(&payload)) {
    it->second.firmware = firmware_text(*f);
  }
}

void Amfitrack::poll(hal::Nanos now) {
  fresh_.clear();
  link_.service(now);
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
    } else {
      on_reply(*p, *pl.payload, now);
    }
  }
  // Rate: frame-id steps over the reception time of a window of polls. Frames arriving in bursts
  // (USB, scheduling) share a reception stamp; the window averages that out.
  if (!fresh_.empty()) {
    if (!rate_window_open_) {
      rate_window_open_ = true;
      rate_window_start_ = now;
      rate_window_ids_ = 0;
    } else if (now - rate_window_start_ >= kRateWindow) {
      rate_hz_ = 1e9 * rate_window_ids_ / static_cast<double>((now - rate_window_start_).count());
      rate_window_start_ = now;
      rate_window_ids_ = 0;
    }
  }
  if (link_.failed()) return;  // nothing to keep alive; the link reconnects by itself
  if (!keepalive_sent_ || now - last_keepalive_ >= config_.keepalive_period) {
    if (send(request_device_id(packet_number_++))) ++counters_.keepalives_sent;
    keepalive_sent_ = true;
    last_keepalive_ = now;
  }
}

}  // namespace amfitrack
