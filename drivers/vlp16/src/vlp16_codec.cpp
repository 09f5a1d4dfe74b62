#include "vlp16/vlp16_codec.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace vlp16 {
namespace {

uint16_t get16(const uint8_t* p) {
  return static_cast<uint16_t>(p[0] | p[1] << 8);
}
uint32_t get32(const uint8_t* p) {
  return static_cast<uint32_t>(p[0]) | static_cast<uint32_t>(p[1]) << 8 |
         static_cast<uint32_t>(p[2]) << 16 | static_cast<uint32_t>(p[3]) << 24;
}
void put16(uint8_t* p, uint16_t v) {
  p[0] = static_cast<uint8_t>(v);
  p[1] = static_cast<uint8_t>(v >> 8);
}
void put32(uint8_t* p, uint32_t v) {
  for (int i = 0; i < 4; ++i)
    p[i] = static_cast<uint8_t>(v >> (8 * i));
}

constexpr size_t kBlockSize = 100;
constexpr size_t kTimestampOffset = 1200;
constexpr size_t kModeOffset = 1204;
constexpr size_t kProductOffset = 1205;
constexpr uint8_t kFlag0 = 0xFF;
constexpr uint8_t kFlag1 = 0xEE;

constexpr size_t kPosTimestampOffset = 198;
constexpr size_t kPosPpsOffset = 202;
constexpr size_t kPosNmeaOffset = 206;

LaserTable make_table(const std::array<double, kLasers>& elevation_deg,
                      const std::array<double, kLasers>& offset_mm) {
  LaserTable t;
  std::array<size_t, kLasers> order{};
  for (size_t i = 0; i < kLasers; ++i) {
    order[i] = i;
    t.elevation_rad[i] = elevation_deg[i] * std::numbers::pi / 180.0;
    t.vertical_offset_m[i] = offset_mm[i] * 1e-3;
    t.cos_elevation[i] = static_cast<float>(std::cos(t.elevation_rad[i]));
    t.sin_elevation[i] = static_cast<float>(std::sin(t.elevation_rad[i]));
  }
  std::sort(order.begin(), order.end(),
            [&](size_t a, size_t b) { return elevation_deg[a] < elevation_deg[b]; });
  for (size_t r = 0; r < kLasers; ++r)
    t.ring[order[r]] = static_cast<uint8_t>(r);
  return t;
}

constexpr std::array<double, kLasers> kVlp16OffsetMm = {
    11.2, -0.7, 9.7, -2.2, 8.1, -3.7, 6.6, -5.1, 5.1, -6.6, 3.7, -8.1, 2.2, -9.7, 0.7, -11.2};

// cos/sin of every azimuth in 0.01 degree steps (interpolated azimuths are rounded to these,
// as the open decoders do: 0.0001745 rad, 1.7 cm at 100 m).
struct AzimuthTable {
  std::vector<float> cos_az;
  std::vector<float> sin_az;
  AzimuthTable() : cos_az(kAzimuthUnits), sin_az(kAzimuthUnits) {
    for (uint32_t a = 0; a < kAzimuthUnits; ++a) {
      const double rad = a * std::numbers::pi / 18000.0;
      cos_az[a] = static_cast<float>(std::cos(rad));
      sin_az[a] = static_cast<float>(std::sin(rad));
    }
  }
};
const AzimuthTable& azimuth_table() {
  static const AzimuthTable kTable;
  return kTable;
}

}  // namespace

std::string_view to_string(ReturnMode m) {
  switch (m) {
    case ReturnMode::kStrongest:
      return "strongest";
    case ReturnMode::kLast:
      return "last";
    case ReturnMode::kDual:
      return "dual";
  }
  return "?";
}

std::string_view to_string(Product p) {
  switch (p) {
    case Product::kVlp16Early:
      return "VLP-16 (early firmware, 0x21)";
    case Product::kVlp16:
      return "VLP-16 / Puck LITE (0x22)";
    case Product::kPuckHiRes:
      return "Puck Hi-Res (0x24)";
  }
  return "?";
}

std::string_view to_string(DecodeError e) {
  switch (e) {
    case DecodeError::kNone:
      return "ok";
    case DecodeError::kWrongSize:
      return "wrong_size";
    case DecodeError::kBadBlockFlag:
      return "bad_block_flag";
    case DecodeError::kBadAzimuth:
      return "bad_azimuth";
    case DecodeError::kUnknownReturnMode:
      return "unknown_return_mode";
    case DecodeError::kUnknownProduct:
      return "unknown_product";
    case DecodeError::kBadTimestamp:
      return "bad_timestamp";
    case DecodeError::kCount:
      break;
  }
  return "?";
}

DecodeError parse_data_packet(std::span<const uint8_t> bytes, RawDataPacket& out) {
  if (bytes.size() != kDataPacketSize) return DecodeError::kWrongSize;
  const uint8_t mode = bytes[kModeOffset];
  if (mode != 0x37 && mode != 0x38 && mode != 0x39) return DecodeError::kUnknownReturnMode;
  const uint8_t product = bytes[kProductOffset];
  if (product != 0x21 && product != 0x22 && product != 0x24) return DecodeError::kUnknownProduct;
  const uint32_t ts = get32(&bytes[kTimestampOffset]);
  if (ts >= kHourUs) return DecodeError::kBadTimestamp;
  for (size_t b = 0; b < kBlocks; ++b) {
    const uint8_t* blk = &bytes[b * kBlockSize];
    if (blk[0] != kFlag0 || blk[1] != kFlag1) return DecodeError::kBadBlockFlag;
    const uint16_t az = get16(blk + 2);
    if (az >= kAzimuthUnits) return DecodeError::kBadAzimuth;
    RawBlock& rb = out.blocks[b];
    rb.azimuth = az;
    for (size_t k = 0; k < kChannels; ++k) {
      rb.distance[k] = get16(blk + 4 + 3 * k);
      rb.intensity[k] = blk[4 + 3 * k + 2];
    }
  }
  out.timestamp_us = ts;
  out.mode = static_cast<ReturnMode>(mode);
  out.product = static_cast<Product>(product);
  return DecodeError::kNone;
}

std::array<uint8_t, kDataPacketSize> encode_data_packet(const RawDataPacket& p) {
  std::array<uint8_t, kDataPacketSize> bytes{};
  for (size_t b = 0; b < kBlocks; ++b) {
    uint8_t* blk = &bytes[b * kBlockSize];
    blk[0] = kFlag0;
    blk[1] = kFlag1;
    put16(blk + 2, p.blocks[b].azimuth);
    for (size_t k = 0; k < kChannels; ++k) {
      put16(blk + 4 + 3 * k, p.blocks[b].distance[k]);
      blk[4 + 3 * k + 2] = p.blocks[b].intensity[k];
    }
  }
  put32(&bytes[kTimestampOffset], p.timestamp_us);
  bytes[kModeOffset] = static_cast<uint8_t>(p.mode);
  bytes[kProductOffset] = static_cast<uint8_t>(p.product);
  return bytes;
}

DecodeError parse_position_packet(std::span<const uint8_t> bytes, PositionPacket& out) {
  if (bytes.size() != kPositionPacketSize) return DecodeError::kWrongSize;
  const uint32_t ts = get32(&bytes[kPosTimestampOffset]);
  if (ts >= kHourUs) return DecodeError::kBadTimestamp;
  out.timestamp_us = ts;
  out.pps = static_cast<PpsStatus>(std::min<uint8_t>(bytes[kPosPpsOffset], 3));
  out.nmea.clear();
  for (size_t i = kPosNmeaOffset; i < bytes.size(); ++i) {
    const char c = static_cast<char>(bytes[i]);
    if (c == '\0' || c == '\r' || c == '\n') break;
    out.nmea.push_back(c >= 0x20 && c < 0x7F ? c : '?');
  }
  return DecodeError::kNone;
}

std::array<uint8_t, kPositionPacketSize> encode_position_packet(const PositionPacket& p) {
  std::array<uint8_t, kPositionPacketSize> bytes{};
  put32(&bytes[kPosTimestampOffset], p.timestamp_us);
  bytes[kPosPpsOffset] = static_cast<uint8_t>(p.pps);
  const size_t room = bytes.size() - kPosNmeaOffset - 2;
  const size_t n = std::min(p.nmea.size(), room);
  std::copy_n(p.nmea.begin(), n, bytes.begin() + kPosNmeaOffset);
  bytes[kPosNmeaOffset + n] = '\r';
  bytes[kPosNmeaOffset + n + 1] = '\n';
  return bytes;
}

const LaserTable& laser_table(Product p) {
  static const LaserTable kVlp16 =
      make_table({-15, 1, -13, 3, -11, 5, -9, 7, -7, 9, -5, 11, -3, 13, -1, 15}, kVlp16OffsetMm);
  static const LaserTable kHiRes = make_table(
      {-10, 0.67, -8.67, 2, -7.33, 3.33, -6, 4.67, -4.67, 6, -3.33, 7.33, -2, 8.67, -0.67, 10},
      kVlp16OffsetMm);
  return p == Product::kPuckHiRes ? kHiRes : kVlp16;
}

uint16_t block_azimuth_gap(const RawDataPacket& p, size_t block) {
  const size_t step = p.mode == ReturnMode::kDual ? 2 : 1;
  size_t first = block - block % step;         // the first block of this firing (pair in dual mode)
  if (first + step >= kBlocks) first -= step;  // the last firing reuses the previous gap
  const uint32_t a = p.blocks[first].azimuth;
  const uint32_t b = p.blocks[first + step].azimuth;
  return static_cast<uint16_t>((b + kAzimuthUnits - a) % kAzimuthUnits);
}

size_t decode_points(const RawDataPacket& p, const DecodeOptions& options, std::span<Point> out) {
  const LaserTable& lt = laser_table(p.product);
  const AzimuthTable& at = azimuth_table();
  const bool dual = p.mode == ReturnMode::kDual;
  const auto min_units =
      static_cast<uint32_t>(static_cast<double>(options.min_range_m) / kDistanceUnitM);
  const auto max_units =
      static_cast<uint32_t>(static_cast<double>(options.max_range_m) / kDistanceUnitM);
  size_t n = 0;
  for (size_t b = 0; b < kBlocks; ++b) {
    const RawBlock& blk = p.blocks[b];
    const double gap = block_azimuth_gap(p, b);
    const size_t seq_base = dual ? (b - b % 2) : 2 * b;
    const bool is_last = dual ? (b % 2 == 0) : p.mode == ReturnMode::kLast;
    for (size_t k = 0; k < kChannels; ++k) {
      const uint16_t d = blk.distance[k];
      const bool no_return = d == 0 && options.no_return_range_m > 0.0f;
      if (!no_return && (d == 0 || d < min_units || d > max_units)) continue;
      // Dual: the strongest block repeats the last block's return when there was only one.
      if (dual && b % 2 == 1 && p.blocks[b - 1].distance[k] == d &&
          p.blocks[b - 1].intensity[k] == blk.intensity[k]) {
        continue;
      }
      if (n >= out.size()) return n;
      const size_t laser = k % kLasers;
      const size_t firing = k / kLasers;
      const double dt =
          kLaserSpacingUs * static_cast<double>(laser) + kSequenceUs * static_cast<double>(firing);
      const auto az = static_cast<uint32_t>(
          (blk.azimuth + static_cast<uint32_t>(std::lround(gap * dt / kBlockUs))) % kAzimuthUnits);
      const float r = no_return ? options.no_return_range_m
                                : static_cast<float>(d) * static_cast<float>(kDistanceUnitM);
      const float xy = r * lt.cos_elevation[laser];
      Point& pt = out[n++];
      pt.x_m = xy * at.cos_az[az];
      pt.y_m = -xy * at.sin_az[az];
      pt.z_m = r * lt.sin_elevation[laser] + static_cast<float>(lt.vertical_offset_m[laser]);
      pt.distance_m = r;
      pt.azimuth = static_cast<uint16_t>(az);
      pt.intensity = blk.intensity[k];
      pt.laser = static_cast<uint8_t>(laser);
      pt.ring = lt.ring[laser];
      pt.block = static_cast<uint8_t>(b);
      pt.channel = static_cast<uint8_t>(k);
      pt.last_return = is_last;
      pt.no_return = no_return;
      pt.time_offset_us = static_cast<float>(kSequenceUs * static_cast<double>(seq_base + firing) +
                                             kLaserSpacingUs * static_cast<double>(laser));
    }
  }
  return n;
}

}  // namespace vlp16
