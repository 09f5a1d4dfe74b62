#pragma once
// Assembles decoded packets into scans (one revolution each), cut where the interpolated azimuth
// passes the configured cut angle. Tracks the sensor's clock (µs past the hour, unwrapped at
// the hour), maps it to the host's monotonic clock, and detects lost packets from timestamp
// gaps. Pure: host reception times are passed in; buffers are allocated once.
#include <cstdint>
#include <vector>

#include "hal/clock.hpp"
#include "vlp16/vlp16_codec.hpp"

namespace vlp16 {

struct ScanConfig {
  uint16_t cut_azimuth = 0;     // 0.01 degree; 0 = straight ahead of the sensor
  size_t max_points = 160'000;  // per scan (dual return at 300 rpm needs ~116 k)
  DecodeOptions decode;
};

struct Scan {
  std::vector<Point> points;  // time_offset_us is relative to `start`
  hal::Nanos start{0};        // host time of the first firing in the scan
  hal::Nanos end{0};          // host time of the last point
  uint32_t packets = 0;
  uint32_t lost_packets = 0;  // inside this scan, from timestamp gaps
  bool partial = false;       // did not start at the cut (the first scan after start-up)
  bool truncated = false;     // more points than max_points (the rest were dropped)
  ReturnMode mode = ReturnMode::kStrongest;
  Product product = Product::kVlp16;
};

struct AssemblerStats {
  uint64_t packets = 0;
  uint64_t lost_packets = 0;
  uint64_t duplicates = 0;  // timestamp not after the previous packet's: dropped
  uint64_t hour_rollovers = 0;
  uint64_t scans = 0;
  uint64_t points = 0;
};

class ScanAssembler {
 public:
  explicit ScanAssembler(const ScanConfig& config);

  // One parsed packet, received at `host_stamp`. Returns the scan it completed (valid until the
  // next completed scan), or nullptr.
  const Scan* add(const RawDataPacket& packet, hal::Nanos host_stamp);

  [[nodiscard]] const AssemblerStats& stats() const { return stats_; }
  // Sensor time (µs, unwrapped) -> host monotonic offset estimate, in ns.
  [[nodiscard]] int64_t clock_offset_ns() const { return offset_ns_; }
  // The packet period of a return mode (µs): 1327.104 single, 663.552 dual.
  static double packet_period_us(ReturnMode mode);

 private:
  void start_scan(hal::Nanos start, bool partial);

  ScanConfig config_;
  std::vector<Point> packet_points_;
  Scan scans_[2];
  int current_ = 0;
  bool started_ = false;
  int32_t last_rel_ = -1;  // previous point's azimuth relative to the cut
  // sensor clock
  bool have_time_ = false;
  uint32_t last_ts_ = 0;
  int64_t hour_base_us_ = 0;
  int64_t last_unwrapped_us_ = 0;
  int64_t offset_ns_ = 0;
  int64_t window_min_ns_ = 0;
  int64_t window_start_us_ = 0;
  AssemblerStats stats_;
};

}  // namespace vlp16
