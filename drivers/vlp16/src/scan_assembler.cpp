#include "vlp16/scan_assembler.hpp"

#include <cmath>
#include <limits>

namespace vlp16 {
namespace {
// The host-minus-sensor offset is the minimum over a window (reception adds latency, never
// removes it); windows of 2 s follow slow drift of the sensor's clock.
constexpr int64_t kOffsetWindowUs = 2'000'000;
}  // namespace

double ScanAssembler::packet_period_us(ReturnMode mode) {
  return mode == ReturnMode::kDual ? kBlockUs * kBlocks / 2 : kBlockUs * kBlocks;
}

ScanAssembler::ScanAssembler(const ScanConfig& config)
    : config_(config), packet_points_(kReturnsPerPacket) {
  for (Scan& s : scans_)
    s.points.reserve(config.max_points);
}

void ScanAssembler::start_scan(hal::Nanos start, bool partial) {
  Scan& s = scans_[current_];
  s.points.clear();
  s.start = start;
  s.end = start;
  s.packets = 0;
  s.lost_packets = 0;
  s.partial = partial;
  s.truncated = false;
}

const Scan* ScanAssembler::add(const RawDataPacket& p, hal::Nanos host_stamp) {
  // Sensor clock: unwrap the hour, detect gaps and duplicates.
  const double period = packet_period_us(p.mode);
  int64_t unwrapped = hour_base_us_ + p.timestamp_us;
  uint32_t lost = 0;
  if (have_time_) {
    if (p.timestamp_us < last_ts_ && last_ts_ - p.timestamp_us > kHourUs / 2) {
      hour_base_us_ += kHourUs;
      unwrapped += kHourUs;
      ++stats_.hour_rollovers;
    }
    const int64_t dt = unwrapped - last_unwrapped_us_;
    if (dt <= 0) {
      ++stats_.duplicates;
      return nullptr;
    }
    if (static_cast<double>(dt) > 1.5 * period) {
      lost = static_cast<uint32_t>(std::lround(static_cast<double>(dt) / period) - 1);
    }
  }
  have_time_ = true;
  last_ts_ = p.timestamp_us;
  last_unwrapped_us_ = unwrapped;
  ++stats_.packets;
  stats_.lost_packets += lost;

  // Host time of the packet's first firing: the packet leaves after its last firing.
  const auto end_of_packet_us = unwrapped + std::llround(period);
  const int64_t sample = host_stamp.count() - end_of_packet_us * 1000;
  if (stats_.packets == 1 || unwrapped - window_start_us_ > kOffsetWindowUs) {
    // A new window: keep the better of the old estimate and the first sample.
    offset_ns_ = stats_.packets == 1 ? sample : std::min(window_min_ns_, sample);
    window_min_ns_ = sample;
    window_start_us_ = unwrapped;
  } else {
    window_min_ns_ = std::min(window_min_ns_, sample);
    offset_ns_ = std::min(offset_ns_, sample);
  }
  const hal::Nanos packet_start(unwrapped * 1000 + offset_ns_);

  if (!started_) {
    started_ = true;
    start_scan(packet_start, true);
  }
  const size_t n = decode_points(p, config_.decode, packet_points_);
  const Scan* completed = nullptr;
  Scan* scan = &scans_[current_];
  scan->lost_packets += lost;
  scan->mode = p.mode;
  scan->product = p.product;
  ++scan->packets;
  for (size_t i = 0; i < n; ++i) {
    Point pt = packet_points_[i];
    const int32_t rel =
        static_cast<int32_t>((pt.azimuth + kAzimuthUnits - config_.cut_azimuth) % kAzimuthUnits);
    // A large backwards step of the relative azimuth is the wrap past the cut angle.
    if (last_rel_ >= 0 && rel + static_cast<int32_t>(kAzimuthUnits / 2) < last_rel_) {
      completed = scan;
      ++stats_.scans;
      current_ = 1 - current_;
      const hal::Nanos t(
          packet_start.count() +
          static_cast<int64_t>(std::llround(static_cast<double>(pt.time_offset_us) * 1000.0)));
      start_scan(t, false);
      scan = &scans_[current_];
      scan->mode = p.mode;
      scan->product = p.product;
      scan->packets = 1;
    }
    last_rel_ = rel;
    const int64_t t_ns =
        packet_start.count() +
        static_cast<int64_t>(std::llround(static_cast<double>(pt.time_offset_us) * 1000.0));
    if (scan->points.size() >= config_.max_points) {
      scan->truncated = true;
      continue;
    }
    pt.time_offset_us = static_cast<float>(static_cast<double>(t_ns - scan->start.count()) / 1000);
    scan->points.push_back(pt);
    scan->end = hal::Nanos(t_ns);
    ++stats_.points;
  }
  return completed;
}

}  // namespace vlp16
