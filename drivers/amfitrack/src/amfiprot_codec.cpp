#include "amfitrack/amfiprot_codec.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace amfitrack {
namespace {

constexpr std::array<uint8_t, 256> make_crc_table() {
  std::array<uint8_t, 256> t{};
  for (int i = 0; i < 256; ++i) {
    auto c = static_cast<uint8_t>(i);
    for (int b = 0; b < 8; ++b)
      c = static_cast<uint8_t>((c & 0x80) ? (c << 1) ^ 0x2F : c << 1);
    t[static_cast<size_t>(i)] = c;
  }
  return t;
}
constexpr std::array<uint8_t, 256> kCrcTable = make_crc_table();

int32_t s24(const uint8_t* p) {
  int32_t v = p[0] | p[1] << 8 | p[2] << 16;
  if (v & 0x800000) v -= 1 << 24;
  return v;
}
uint32_t u24(const uint8_t* p) {
  return static_cast<uint32_t>(p[0] | p[1] << 8 | p[2] << 16);
}
int16_t s16(const uint8_t* p) {
  return static_cast<int16_t>(static_cast<uint16_t>(p[0] | p[1] << 8));
}
uint16_t u16(const uint8_t* p) {
  return static_cast<uint16_t>(p[0] | p[1] << 8);
}
uint32_t u32(const uint8_t* p) {
  return static_cast<uint32_t>(p[0]) | static_cast<uint32_t>(p[1]) << 8 |
         static_cast<uint32_t>(p[2]) << 16 | static_cast<uint32_t>(p[3]) << 24;
}
void put24(std::vector<uint8_t>& v, size_t at, int64_t x) {
  const auto u = static_cast<uint32_t>(x) & 0xFFFFFF;
  v[at] = static_cast<uint8_t>(u);
  v[at + 1] = static_cast<uint8_t>(u >> 8);
  v[at + 2] = static_cast<uint8_t>(u >> 16);
}
void put16(std::vector<uint8_t>& v, size_t at, int64_t x) {
  const auto u = static_cast<uint16_t>(x);
  v[at] = static_cast<uint8_t>(u);
  v[at + 1] = static_cast<uint8_t>(u >> 8);
}
int64_t scaled(double value, double unit, int64_t lo, int64_t hi) {
  if (!std::isfinite(value)) return 0;
  return std::clamp<int64_t>(std::llround(value / unit), lo, hi);
}

Packet common_request(uint8_t number, uint8_t destination, uint8_t cmd,
                      std::initializer_list<uint8_t> args = {}) {
  Packet p;
  p.header.packet_number = number;
  p.header.payload_type = payload_type::kCommon;
  p.header.source = kPcTxId;
  p.header.destination = destination;
  p.payload.reserve(1 + args.size());
  p.payload.push_back(cmd);
  for (const uint8_t a : args)
    p.payload.push_back(a);
  p.header.payload_length = static_cast<uint8_t>(p.payload.size());
  return p;
}

}  // namespace

uint8_t crc8(std::span<const uint8_t> bytes) {
  uint8_t c = 0;
  for (const uint8_t b : bytes)
    c = kCrcTable[c ^ b];
  return c;
}

std::string_view to_string(PacketError e) {
  switch (e) {
    case PacketError::kTooShort:
      return "too_short";
    case PacketError::kBadHeaderCrc:
      return "bad_header_crc";
    case PacketError::kPayloadTooLong:
      return "payload_too_long";
    case PacketError::kBadPayloadCrc:
      return "bad_payload_crc";
    case PacketError::kCount:
      break;
  }
  return "?";
}

std::string_view to_string(PayloadError e) {
  switch (e) {
    case PayloadError::kUnknownType:
      return "unknown_type";
    case PayloadError::kUnknownCommand:
      return "unknown_command";
    case PayloadError::kBadLength:
      return "bad_length";
    case PayloadError::kCount:
      break;
  }
  return "?";
}

ParsedPacket parse_packet(std::span<const uint8_t> b) {
  ParsedPacket r;
  if (b.size() < kHeaderSize) return r;
  if (crc8(b.first(6)) != b[6]) {
    r.error = PacketError::kBadHeaderCrc;
    return r;
  }
  const size_t len = b[0];
  if (len > kMaxPayload) {
    r.error = PacketError::kPayloadTooLong;
    return r;
  }
  const size_t total = len == 0 ? kHeaderSize : kHeaderSize + len + 1;
  if (b.size() < total) return r;  // kTooShort
  if (len > 0 && crc8(b.subspan(kHeaderSize, len)) != b[kHeaderSize + len]) {
    r.error = PacketError::kBadPayloadCrc;
    return r;
  }
  Packet p;
  p.header.payload_length = static_cast<uint8_t>(len);
  p.header.ack = static_cast<AckType>(b[1] >> 6);
  p.header.ttl = b[1] & 0x3F;
  p.header.packet_number = b[2];
  p.header.payload_type = b[3];
  p.header.source = b[4];
  p.header.destination = b[5];
  p.payload.assign(b.begin() + kHeaderSize,
                   b.begin() + static_cast<std::ptrdiff_t>(kHeaderSize + len));
  r.packet = std::move(p);
  r.consumed = total;
  return r;
}

std::vector<uint8_t> encode_packet(const Packet& p) {
  const size_t len = std::min(p.payload.size(), kMaxPayload);
  std::vector<uint8_t> out(len == 0 ? kHeaderSize : kHeaderSize + len + 1);
  out[0] = static_cast<uint8_t>(len);
  out[1] = static_cast<uint8_t>(static_cast<uint8_t>(p.header.ack) << 6 | (p.header.ttl & 0x3F));
  out[2] = p.header.packet_number;
  out[3] = p.header.payload_type;
  out[4] = p.header.source;
  out[5] = p.header.destination;
  out[6] = crc8(std::span<const uint8_t>(out).first(6));
  if (len > 0) {
    std::copy_n(p.payload.begin(), len, out.begin() + kHeaderSize);
    out[kHeaderSize + len] = crc8(std::span<const uint8_t>(out).subspan(kHeaderSize, len));
  }
  return out;
}

FramingStats& operator+=(FramingStats& a, const FramingStats& b) {
  a.frames += b.frames;
  a.bad_cobs += b.bad_cobs;
  a.overlong += b.overlong;
  a.bad_packet += b.bad_packet;
  for (size_t i = 0; i < a.packet_errors.size(); ++i)
    a.packet_errors[i] += b.packet_errors[i];
  return a;
}

ParsedPacket parse_hid_report(std::span<const uint8_t> report) {
  // [report id][length byte][packet...]: the two prefix bytes are not trusted (nobody checks
  // them); the packet's own header and CRCs decide.
  if (report.size() < 2) return ParsedPacket{};
  return parse_packet(report.subspan(2));
}

std::array<uint8_t, kHidReportSize> encode_hid_report(const Packet& p) {
  std::array<uint8_t, kHidReportSize> r{};
  r[0] = 0x01;
  const auto bytes = encode_packet(p);
  std::copy_n(bytes.begin(), std::min(bytes.size(), r.size() - 1), r.begin() + 1);
  return r;
}

std::vector<uint8_t> cobs_encode(std::span<const uint8_t> bytes) {
  std::vector<uint8_t> out;
  out.reserve(bytes.size() + bytes.size() / 254 + 2);
  size_t code_at = out.size();
  out.push_back(0);
  uint8_t code = 1;
  for (const uint8_t b : bytes) {
    if (b == 0) {
      out[code_at] = code;
      code_at = out.size();
      out.push_back(0);
      code = 1;
    } else {
      out.push_back(b);
      if (++code == 0xFF) {
        out[code_at] = code;
        code_at = out.size();
        out.push_back(0);
        code = 1;
      }
    }
  }
  out[code_at] = code;
  return out;
}

std::optional<std::vector<uint8_t>> cobs_decode(std::span<const uint8_t> in) {
  std::vector<uint8_t> out;
  out.reserve(in.size());
  size_t i = 0;
  while (i < in.size()) {
    const uint8_t code = in[i++];
    if (code == 0) return std::nullopt;
    for (uint8_t k = 1; k < code; ++k) {
      if (i >= in.size() || in[i] == 0) return std::nullopt;
      out.push_back(in[i++]);
    }
    if (code != 0xFF && i < in.size()) out.push_back(0);
  }
  return out;
}

void CobsStreamDecoder::feed(std::span<const uint8_t> bytes) {
  // A COBS-encoded packet of at most 62 bytes takes at most 63 bytes.
  constexpr size_t kMaxEncoded = kMaxPacket + 1;
  for (const uint8_t b : bytes) {
    if (b != 0) {
      if (discarding_) continue;
      frame_.push_back(b);
      if (frame_.size() > kMaxEncoded) {
        ++stats_.overlong;
        frame_.clear();
        discarding_ = true;
      }
      continue;
    }
    // Delimiter: a frame ends (or garbage ends and the stream is in sync again).
    if (discarding_) {
      discarding_ = false;
      continue;
    }
    if (frame_.empty()) continue;  // repeated delimiters
    const auto decoded = cobs_decode(frame_);
    frame_.clear();
    if (!decoded) {
      ++stats_.bad_cobs;
      continue;
    }
    auto parsed = parse_packet(*decoded);
    if (!parsed.packet || parsed.consumed != decoded->size()) {
      ++stats_.bad_packet;
      ++stats_.packet_errors[static_cast<size_t>(parsed.packet ? PacketError::kTooShort
                                                               : parsed.error)];
      continue;
    }
    ++stats_.frames;
    if (ready_head_ > 0 && ready_head_ == ready_.size()) {
      ready_.clear();
      ready_head_ = 0;
    }
    ready_.push_back(std::move(*parsed.packet));
  }
}

std::optional<Packet> CobsStreamDecoder::next() {
  if (ready_head_ >= ready_.size()) return std::nullopt;
  return std::move(ready_[ready_head_++]);
}

ParsedPayload decode_payload(const Packet& p) {
  ParsedPayload r;
  const auto& d = p.payload;
  auto fail = [&](PayloadError e) {
    r.error = e;
    return r;
  };
  switch (p.header.payload_type) {
    case payload_type::kSensorMeasurement: {
      const bool old = d.size() == kSensorMeasurementOldSize;
      if (d.size() != kSensorMeasurementSize && !old) return fail(PayloadError::kBadLength);
      const uint8_t* b = d.data();
      SensorMeasurement m;
      m.old_layout = old;
      for (size_t i = 0; i < 3; ++i)
        m.position_m[i] = s24(b + 3 * i) * 1e-5;
      for (size_t i = 0; i < 4; ++i)
        m.quaternion_xyzw[i] = s24(b + 9 + 3 * i) * 1e-6;
      m.sensor_status = b[21];
      m.tracked_source = b[22];
      m.calculation_id = u16(b + 23);
      for (size_t i = 0; i < 3; ++i) {
        m.accel_g[i] = s16(b + 25 + 2 * i) * 4.0 / 32767.0;
        m.gyro_dps[i] = s16(b + 31 + 2 * i) * 0.070;
      }
      if (old) {
        m.pose_state_raw = b[37];
        m.quality_raw = b[38];
        m.gpio = u16(b + 39);
        m.rssi = static_cast<int8_t>(b[41]);
        m.frame_id = u24(b + 42);
      } else {
        for (size_t i = 0; i < 3; ++i)
          m.mag_ut[i] = s16(b + 37 + 2 * i) * 400.0 / 32767.0;
        m.temperature_c = b[43] / 2.0 - 30.0;
        m.pose_state_raw = b[44];
        m.quality_raw = b[45];
        m.gpio = u16(b + 46);
        m.rssi = static_cast<int8_t>(b[48]);
        m.frame_id = u24(b + 49);
      }
      r.payload = m;
      return r;
    }
    case payload_type::kSourceMeasurement:
      r.payload = SourceMeasurement{d};
      return r;
    case payload_type::kSuccess:
    case payload_type::kNotImplemented:
    case payload_type::kFailure:
    case payload_type::kInvalidRequest:
      r.payload = StatusReply{p.header.payload_type};
      return r;
    case payload_type::kCommon:
      break;
    default:
      return fail(PayloadError::kUnknownType);
  }
  if (d.empty()) return fail(PayloadError::kBadLength);
  const uint8_t* b = d.data() + 1;
  const size_t n = d.size() - 1;
  switch (d[0]) {
    case command::kReplyDeviceId:
      if (n < 13) return fail(PayloadError::kBadLength);
      r.payload = DeviceIdReply{b[0], {u32(b + 1), u32(b + 5), u32(b + 9)}};
      return r;
    case command::kReplyFirmwareVersion:
      if (n < 16) return fail(PayloadError::kBadLength);
      r.payload = FirmwareVersionReply{{u32(b), u32(b + 4), u32(b + 8), u32(b + 12)}};
      return r;
    case command::kReplyDeviceName: {
      const auto* end = std::find(b, b + n, uint8_t{0});
      r.payload = DeviceNameReply{std::string(b, end)};
      return r;
    }
    case command::kReplyConfigValueUid:
      if (n < 5) return fail(PayloadError::kBadLength);
      r.payload = ConfigValueReply{u32(b), b[4], std::vector<uint8_t>(b + 5, b + n)};
      return r;
    default:
      return fail(PayloadError::kUnknownCommand);
  }
}

Packet request_device_id(uint8_t number, uint8_t destination) {
  return common_request(number, destination, command::kRequestDeviceId);
}
Packet request_firmware_version(uint8_t number, uint8_t destination) {
  return common_request(number, destination, command::kRequestFirmwareVersion);
}
Packet request_device_name(uint8_t number, uint8_t destination) {
  return common_request(number, destination, command::kRequestDeviceName);
}
Packet request_config_value(uint8_t number, uint8_t destination, uint32_t uid) {
  return common_request(number, destination, command::kRequestConfigValueUid,
                        {static_cast<uint8_t>(uid), static_cast<uint8_t>(uid >> 8),
                         static_cast<uint8_t>(uid >> 16), static_cast<uint8_t>(uid >> 24)});
}

Packet sensor_measurement_packet(const SensorMeasurement& m, uint8_t source, uint8_t number) {
  Packet p;
  p.header.packet_number = number;
  p.header.payload_type = payload_type::kSensorMeasurement;
  p.header.source = source;
  p.header.destination = kPcTxId;
  auto& v = p.payload;
  v.assign(kSensorMeasurementSize, 0);
  constexpr int64_t kS24Min = -(1 << 23);
  constexpr int64_t kS24Max = (1 << 23) - 1;
  for (size_t i = 0; i < 3; ++i)
    put24(v, 3 * i, scaled(m.position_m[i], 1e-5, kS24Min, kS24Max));
  for (size_t i = 0; i < 4; ++i)
    put24(v, 9 + 3 * i, scaled(m.quaternion_xyzw[i], 1e-6, kS24Min, kS24Max));
  v[21] = m.sensor_status;
  v[22] = m.tracked_source;
  put16(v, 23, m.calculation_id);
  for (size_t i = 0; i < 3; ++i) {
    put16(v, 25 + 2 * i, scaled(m.accel_g[i], 4.0 / 32767.0, -32768, 32767));
    put16(v, 31 + 2 * i, scaled(m.gyro_dps[i], 0.070, -32768, 32767));
    put16(v, 37 + 2 * i, scaled(m.mag_ut[i], 400.0 / 32767.0, -32768, 32767));
  }
  v[43] = static_cast<uint8_t>(scaled((m.temperature_c.value_or(25.0) + 30.0) * 2.0, 1.0, 0, 255));
  v[44] = m.pose_state_raw;
  v[45] = m.quality_raw;
  put16(v, 46, m.gpio);
  v[48] = static_cast<uint8_t>(m.rssi);
  put24(v, 49, m.frame_id);
  p.header.payload_length = static_cast<uint8_t>(v.size());
  return p;
}

}  // namespace amfitrack
