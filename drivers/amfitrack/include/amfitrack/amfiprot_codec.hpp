#pragma once
// Amfiprot (Amfitrack Gen 3), pure: bytes <-> typed packets. No I/O, no clock.
// Facts: reference/amfiprot.md. Little-endian, packed; CRC-8/OPENSAFETY (poly 0x2F, init 0,
// no reflection, no final XOR) over the 7-byte header's first 6 bytes and over the payload.
#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace amfitrack {

uint8_t crc8(std::span<const uint8_t> bytes);

inline constexpr size_t kHeaderSize = 7;
inline constexpr size_t kMaxPayload = 54;
inline constexpr size_t kMaxPacket = kHeaderSize + kMaxPayload + 1;  // 62
inline constexpr size_t kHidReportSize = 64;
inline constexpr uint8_t kPcTxId = 0;
inline constexpr uint8_t kBroadcastTxId = 255;

enum class AckType : uint8_t { kNoAck = 0, kRequestAck = 1, kAck = 2, kReply = 3 };

namespace payload_type {
inline constexpr uint8_t kCommon = 0x00;
inline constexpr uint8_t kSourceMeasurement = 0x24;
inline constexpr uint8_t kSensorMeasurement = 0x1A;
inline constexpr uint8_t kSuccess = 0xF0;
inline constexpr uint8_t kNotImplemented = 0xFD;
inline constexpr uint8_t kFailure = 0xFE;
inline constexpr uint8_t kInvalidRequest = 0xFF;
}  // namespace payload_type

namespace command {
inline constexpr uint8_t kRequestDeviceId = 0x00;
inline constexpr uint8_t kReplyDeviceId = 0x01;
inline constexpr uint8_t kRequestFirmwareVersion = 0x03;
inline constexpr uint8_t kReplyFirmwareVersion = 0x04;
inline constexpr uint8_t kRequestDeviceName = 0x08;
inline constexpr uint8_t kReplyDeviceName = 0x09;
inline constexpr uint8_t kRequestConfigValueUid = 0x13;
inline constexpr uint8_t kReplyConfigValueUid = 0x14;
inline constexpr uint8_t kSetConfigValueUid = 0x15;
}  // namespace command

struct Header {
  uint8_t payload_length = 0;  // excluding the payload CRC
  AckType ack = AckType::kNoAck;
  uint8_t ttl = 0;  // bits 5..0 of packet_type
  uint8_t packet_number = 0;
  uint8_t payload_type = 0;
  uint8_t source = 0;       // TX id (0 = PC)
  uint8_t destination = 0;  // TX id (0 = PC, 255 = broadcast)
};

struct Packet {
  Header header;
  std::vector<uint8_t> payload;  // without its CRC
};

enum class PacketError : uint8_t {
  kTooShort,  // fewer bytes than the header (or than header + payload + CRC) needs
  kBadHeaderCrc,
  kPayloadTooLong,  // payload_length > 54
  kBadPayloadCrc,
  kCount
};
std::string_view to_string(PacketError e);

struct ParsedPacket {
  std::optional<Packet> packet;
  PacketError error = PacketError::kTooShort;  // valid when !packet
  size_t consumed = 0;                         // bytes of the packet (when parsed)
};
// Parses one packet at the start of `bytes` (trailing bytes, e.g. HID padding, are ignored).
ParsedPacket parse_packet(std::span<const uint8_t> bytes);
std::vector<uint8_t> encode_packet(const Packet& p);

// HID: IN report = [report id][length byte][packet][padding]; OUT = [0x01][packet][0 ... to 64].
ParsedPacket parse_hid_report(std::span<const uint8_t> report);
std::array<uint8_t, kHidReportSize> encode_hid_report(const Packet& p);

// UART: COBS-encoded packets, each terminated by 0x00.
std::vector<uint8_t> cobs_encode(std::span<const uint8_t> bytes);
std::optional<std::vector<uint8_t>> cobs_decode(std::span<const uint8_t> encoded);

// What a link's framing saw: COBS frames on a UART, input reports on HID.
struct FramingStats {
  uint64_t frames = 0;      // COBS frames / HID reports
  uint64_t bad_cobs = 0;    // frame with an invalid COBS structure (UART only)
  uint64_t overlong = 0;    // garbage longer than any packet before a delimiter (resynchronised)
  uint64_t bad_packet = 0;  // framing fine, packet check failed (see packet_errors)
  std::array<uint64_t, static_cast<size_t>(PacketError::kCount)> packet_errors{};
};

FramingStats& operator+=(FramingStats& a, const FramingStats& b);

// Splits a UART byte stream at 0x00 delimiters and decodes packets; resynchronises at the next
// delimiter after garbage or a torn frame.
class CobsStreamDecoder {
 public:
  void feed(std::span<const uint8_t> bytes);
  std::optional<Packet> next();
  [[nodiscard]] const FramingStats& stats() const { return stats_; }

 private:
  std::vector<uint8_t> frame_;
  std::vector<Packet> ready_;
  size_t ready_head_ = 0;
  bool discarding_ = false;
  FramingStats stats_;
};

// ---- payloads --------------------------------------------------------------------------------

enum class BFieldStatus : uint8_t {
  kTracking = 0,
  kUncertain = 1,
  kNone = 2,
  kTooLow = 3,
  kTooHigh = 4,
  kSourceCoilDefect = 5,
  kSensorCoilDefect = 6,
  kUnknown = 7
};
enum class PoseState : uint8_t { kNoTracking = 0, kTracking = 1, kUncertain = 2 };  // 3..8 start-up

struct SensorMeasurement {
  std::array<double, 3> position_m{};       // sensor in the SOURCE frame
  std::array<double, 4> quaternion_xyzw{};  // as sent (not normalised)
  uint8_t sensor_status = 0;
  uint8_t tracked_source = 0;
  uint16_t calculation_id = 0;
  std::array<double, 3> accel_g{};
  std::array<double, 3> gyro_dps{};
  std::array<double, 3> mag_ut{};
  std::optional<double> temperature_c;  // 52-byte layout only
  uint8_t pose_state_raw = 0;
  uint8_t quality_raw = 0;  // metal distortion as quality (polarity is configured by the gate)
  uint16_t gpio = 0;
  int8_t rssi = 0;
  uint32_t frame_id = 0;  // 24 bits, wraps
  bool old_layout = false;

  [[nodiscard]] bool charging() const { return (sensor_status & 0x04) != 0; }
  [[nodiscard]] bool source_connected() const { return (sensor_status & 0x08) != 0; }
  [[nodiscard]] BFieldStatus bfield() const {
    return static_cast<BFieldStatus>((sensor_status >> 4) & 0x07);
  }
};
inline constexpr size_t kSensorMeasurementSize = 52;
inline constexpr size_t kSensorMeasurementOldSize = 45;

struct DeviceIdReply {
  uint8_t tx_id = 0;
  std::array<uint32_t, 3> uuid{};
};
struct FirmwareVersionReply {
  std::array<uint32_t, 4> words{};
};
struct DeviceNameReply {
  std::string name;
};
struct ConfigValueReply {
  uint32_t uid = 0;
  uint8_t type = 0;
  std::vector<uint8_t> value;  // raw, as typed by `type`
};
// Source measurement (0x24): layout not public; kept raw for diagnostics.
struct SourceMeasurement {
  std::vector<uint8_t> raw;
};
struct StatusReply {
  uint8_t code = 0;  // 0xF0 success, 0xFD not implemented, 0xFE failure, 0xFF invalid request
};

using Payload = std::variant<SensorMeasurement, SourceMeasurement, DeviceIdReply,
                             FirmwareVersionReply, DeviceNameReply, ConfigValueReply, StatusReply>;

enum class PayloadError : uint8_t { kUnknownType, kUnknownCommand, kBadLength, kCount };
std::string_view to_string(PayloadError e);

struct ParsedPayload {
  std::optional<Payload> payload;
  PayloadError error = PayloadError::kUnknownType;
};
ParsedPayload decode_payload(const Packet& p);

// ---- encoders (host requests; the device side for the simulator and tests) -------------------

Packet request_device_id(uint8_t packet_number, uint8_t destination = kBroadcastTxId);
Packet request_firmware_version(uint8_t packet_number, uint8_t destination);
Packet request_device_name(uint8_t packet_number, uint8_t destination);
Packet request_config_value(uint8_t packet_number, uint8_t destination, uint32_t uid);
Packet sensor_measurement_packet(const SensorMeasurement& m, uint8_t source, uint8_t packet_number);

}  // namespace amfitrack
