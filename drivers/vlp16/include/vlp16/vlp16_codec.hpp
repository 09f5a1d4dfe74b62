#pragma once
// Velodyne VLP-16 / Puck LITE / Puck Hi-Res, pure: bytes <-> typed packets, and points with the
// reference's geometry and timing (reference/vlp16.md). No I/O, no clock, no allocation.
//
// Two layers: RawDataPacket is the packet exactly as sent (parse/encode round-trip bit for bit,
// used by the simulator and tests); decode_points() turns one into returns in ROS axes
// (x forward, y left, z up) with per-point azimuth interpolation and time offset.
#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

namespace vlp16 {

inline constexpr size_t kDataPacketSize = 1206;
inline constexpr size_t kPositionPacketSize = 512;
inline constexpr size_t kBlocks = 12;
inline constexpr size_t kChannels = 32;  // per block: two firing sequences of 16 lasers
inline constexpr size_t kLasers = 16;
inline constexpr size_t kReturnsPerPacket = kBlocks * kChannels;  // 384
inline constexpr uint32_t kAzimuthUnits = 36000;                  // 0.01 degree
inline constexpr double kDistanceUnitM = 0.002;
inline constexpr double kLaserSpacingUs = 2.304;
inline constexpr double kSequenceUs = 55.296;
inline constexpr double kBlockUs = 110.592;
inline constexpr uint32_t kHourUs = 3'600'000'000U;

enum class ReturnMode : uint8_t { kStrongest = 0x37, kLast = 0x38, kDual = 0x39 };
enum class Product : uint8_t { kVlp16Early = 0x21, kVlp16 = 0x22, kPuckHiRes = 0x24 };
std::string_view to_string(ReturnMode m);
std::string_view to_string(Product p);

struct RawBlock {
  uint16_t azimuth = 0;                        // 0.01 degree, 0..35999
  std::array<uint16_t, kChannels> distance{};  // 2 mm units, 0 = no return
  std::array<uint8_t, kChannels> intensity{};
};

struct RawDataPacket {
  std::array<RawBlock, kBlocks> blocks{};
  uint32_t timestamp_us = 0;  // past the top of the hour, of the packet's first firing
  ReturnMode mode = ReturnMode::kStrongest;
  Product product = Product::kVlp16;
};

enum class DecodeError : uint8_t {
  kNone = 0,
  kWrongSize,
  kBadBlockFlag,
  kBadAzimuth,  // >= 36000
  kUnknownReturnMode,
  kUnknownProduct,
  kBadTimestamp,  // >= one hour of microseconds
  kCount
};
std::string_view to_string(DecodeError e);

// Parses a 1206-byte data packet; on failure, the reason.
DecodeError parse_data_packet(std::span<const uint8_t> bytes, RawDataPacket& out);
std::array<uint8_t, kDataPacketSize> encode_data_packet(const RawDataPacket& p);

// Position packet (port 8308).
enum class PpsStatus : uint8_t { kAbsent = 0, kSynchronizing = 1, kLocked = 2, kError = 3 };
struct PositionPacket {
  uint32_t timestamp_us = 0;
  PpsStatus pps = PpsStatus::kAbsent;
  std::string nmea;  // the GPRMC sentence without CR/LF (empty when none)
};
DecodeError parse_position_packet(std::span<const uint8_t> bytes, PositionPacket& out);
std::array<uint8_t, kPositionPacketSize> encode_position_packet(const PositionPacket& p);

// Laser geometry of a product.
struct LaserTable {
  std::array<double, kLasers> elevation_rad{};
  std::array<double, kLasers> vertical_offset_m{};
  std::array<uint8_t, kLasers> ring{};  // rank of the elevation: 0 = lowest
  std::array<float, kLasers> cos_elevation{};
  std::array<float, kLasers> sin_elevation{};
};
const LaserTable& laser_table(Product p);

// One return.
struct Point {
  float x_m = 0, y_m = 0, z_m = 0;  // sensor frame, ROS axes
  float distance_m = 0;
  uint16_t azimuth = 0;  // interpolated, 0.01 degree
  uint8_t intensity = 0;
  uint8_t laser = 0;         // 0..15
  uint8_t ring = 0;          // 0 = lowest elevation
  uint8_t block = 0;         // 0..11
  uint8_t channel = 0;       // 0..31
  bool last_return = false;  // dual mode: from the "last" block (else strongest)
  bool no_return = false;    // the beam saw nothing: a point at no_return_range_m along it
  float time_offset_us = 0;  // after the packet timestamp
};

struct DecodeOptions {
  float min_range_m = 0.3f;  // closer returns are the sensor's housing / noise: dropped
  float max_range_m = 130.0f;
  // > 0: a channel without a return (distance 0) still yields a point this far along its beam,
  // flagged no_return: the beam crossed free space up to there (what clears where a pedestrian
  // was when nothing stands behind them). 0: channels without a return are skipped.
  float no_return_range_m = 0.0f;
};

// Returns of one packet into `out` (capacity >= kReturnsPerPacket); returns the count written.
// Zero distances and ranges outside the options are skipped; in dual mode a strongest return
// equal to the last return of the same firing is written once.
size_t decode_points(const RawDataPacket& p, const DecodeOptions& options, std::span<Point> out);

// Per-block azimuth step (0.01 degree units) used for the interpolation of block b.
uint16_t block_azimuth_gap(const RawDataPacket& p, size_t block);

}  // namespace vlp16
