#include <gtest/gtest.h>

#include <random>
#include <string>
#include <vector>

#include "amfitrack/amfiprot_codec.hpp"

namespace am = amfitrack;
using Bytes = std::vector<uint8_t>;

namespace {
Bytes hex(const std::string& text) {
  Bytes out;
  for (size_t i = 0; i + 1 < text.size();) {
    if (text[i] == ' ' || text[i] == '\n') {
      ++i;
      continue;
    }
    out.push_back(static_cast<uint8_t>(std::stoi(text.substr(i, 2), nullptr, 16)));
    i += 2;
  }
  return out;
}

// The reference's 0x1A test vector (built from the description, not captured).
const Bytes kPoseVector =
    hex("34 00 07 1a 02 00 2e 39 30 00 b0 3c ff a0 86 01 00 00 00 00 00 00 23 ca 0a 23 ca 0a "
        "08 01 34 12 00 00 00 00 00 20 00 00 00 00 00 00 64 00 9c ff 00 00 6e 01 e6 0f 00 2d "
        "03 02 01 ef");
const Bytes kRequestDeviceIdVector = hex("01 00 00 00 00 FF 16 00 00");
}  // namespace

TEST(Amfiprot, Crc8IsOpenSafety) {
  const std::string check = "123456789";
  EXPECT_EQ(am::crc8(std::span(reinterpret_cast<const uint8_t*>(check.data()), check.size())),
            0x3E);
}

TEST(Amfiprot, RequestDeviceIdMatchesTheReference) {
  EXPECT_EQ(am::encode_packet(am::request_device_id(0)), kRequestDeviceIdVector);
  const auto parsed = am::parse_packet(kRequestDeviceIdVector);
  ASSERT_TRUE(parsed.packet);
  EXPECT_EQ(parsed.packet->header.destination, am::kBroadcastTxId);
  EXPECT_EQ(parsed.consumed, 9U);
}

TEST(Amfiprot, PoseTestVectorDecodesToTheStatedValues) {
  const auto parsed = am::parse_packet(kPoseVector);
  ASSERT_TRUE(parsed.packet) << am::to_string(parsed.error);
  const auto& h = parsed.packet->header;
  EXPECT_EQ(h.payload_length, 52);
  EXPECT_EQ(h.packet_number, 7);
  EXPECT_EQ(h.payload_type, am::payload_type::kSensorMeasurement);
  EXPECT_EQ(h.source, 2);
  EXPECT_EQ(h.destination, 0);
  EXPECT_EQ(h.ack, am::AckType::kNoAck);

  const auto pl = am::decode_payload(*parsed.packet);
  ASSERT_TRUE(pl.payload);
  const auto& m = std::get<am::SensorMeasurement>(*pl.payload);
  EXPECT_NEAR(m.position_m[0], 0.12345, 1e-12);
  EXPECT_NEAR(m.position_m[1], -0.5, 1e-12);
  EXPECT_NEAR(m.position_m[2], 1.0, 1e-12);
  EXPECT_NEAR(m.quaternion_xyzw[0], 0.0, 1e-12);
  EXPECT_NEAR(m.quaternion_xyzw[2], 0.707107, 1e-12);
  EXPECT_NEAR(m.quaternion_xyzw[3], 0.707107, 1e-12);
  EXPECT_EQ(m.sensor_status, 0x08);
  EXPECT_TRUE(m.source_connected());
  EXPECT_FALSE(m.charging());
  EXPECT_EQ(m.bfield(), am::BFieldStatus::kTracking);
  EXPECT_EQ(m.tracked_source, 1);
  EXPECT_EQ(m.calculation_id, 0x1234);
  EXPECT_NEAR(m.accel_g[2], 8192 * 4.0 / 32767.0, 1e-12);
  EXPECT_NEAR(m.mag_ut[0], 100 * 400.0 / 32767.0, 1e-12);
  EXPECT_NEAR(m.mag_ut[1], -100 * 400.0 / 32767.0, 1e-12);
  ASSERT_TRUE(m.temperature_c);
  EXPECT_DOUBLE_EQ(*m.temperature_c, 25.0);
  EXPECT_EQ(m.pose_state_raw, 1);
  EXPECT_EQ(m.quality_raw, 230);
  EXPECT_EQ(m.gpio, 0x000F);
  EXPECT_EQ(m.rssi, 45);
  EXPECT_EQ(m.frame_id, 0x010203U);
  EXPECT_FALSE(m.old_layout);
}

TEST(Amfiprot, EncoderReproducesTheTestVector) {
  am::SensorMeasurement m;
  m.position_m = {0.12345, -0.5, 1.0};
  m.quaternion_xyzw = {0, 0, 0.7071068, 0.7071068};
  m.sensor_status = 0x08;
  m.tracked_source = 1;
  m.calculation_id = 0x1234;
  m.accel_g = {0, 0, 8192 * 4.0 / 32767.0};
  m.mag_ut = {100 * 400.0 / 32767.0, -100 * 400.0 / 32767.0, 0};
  m.temperature_c = 25.0;
  m.pose_state_raw = 1;
  m.quality_raw = 230;
  m.gpio = 0x000F;
  m.rssi = 45;
  m.frame_id = 0x010203;
  EXPECT_EQ(am::encode_packet(am::sensor_measurement_packet(m, 2, 7)), kPoseVector);
}

TEST(Amfiprot, EveryMalformedVariantIsRejectedForTheRightReason) {
  auto error_of = [](const Bytes& b) {
    const auto p = am::parse_packet(b);
    EXPECT_FALSE(p.packet);
    return p.error;
  };
  EXPECT_EQ(error_of(Bytes(kPoseVector.begin(), kPoseVector.begin() + 6)),
            am::PacketError::kTooShort);
  EXPECT_EQ(error_of(Bytes(kPoseVector.begin(), kPoseVector.end() - 1)), am::PacketError::kTooShort)
      << "payload CRC missing";
  Bytes b = kPoseVector;
  b[6] ^= 0x01;
  EXPECT_EQ(error_of(b), am::PacketError::kBadHeaderCrc);
  b = kPoseVector;
  b[2] = 8;  // header changed, CRC not: header CRC catches it
  EXPECT_EQ(error_of(b), am::PacketError::kBadHeaderCrc);
  b = kPoseVector;
  b[20] ^= 0x40;
  EXPECT_EQ(error_of(b), am::PacketError::kBadPayloadCrc);
  b = kPoseVector;
  b.back() ^= 0xFF;
  EXPECT_EQ(error_of(b), am::PacketError::kBadPayloadCrc);
  // A valid header announcing 55 payload bytes.
  Bytes longer{55, 0, 0, 0x1A, 2, 0, 0};
  longer[6] = am::crc8(std::span(longer).first(6));
  longer.resize(7 + 56, 0);
  EXPECT_EQ(error_of(longer), am::PacketError::kPayloadTooLong);

  // Packet fine, payload wrong length / unknown type / unknown command.
  am::Packet p = *am::parse_packet(kPoseVector).packet;
  p.payload.resize(50);
  EXPECT_EQ(am::decode_payload(p).error, am::PayloadError::kBadLength);
  p.header.payload_type = 0x42;
  EXPECT_EQ(am::decode_payload(p).error, am::PayloadError::kUnknownType);
  am::Packet c = am::request_device_id(0);
  c.payload = {0x77};
  EXPECT_EQ(am::decode_payload(c).error, am::PayloadError::kUnknownCommand);
  c.payload = {am::command::kReplyDeviceId, 1, 2};
  EXPECT_EQ(am::decode_payload(c).error, am::PayloadError::kBadLength);
}

TEST(Amfiprot, OldFortyFiveByteLayoutDispatchesOnLength) {
  Bytes pl(45, 0);
  pl[0] = 0x39;   // x = 0x000039 -> 57e-5 m
  pl[21] = 0x18;  // source connected, B-field uncertain
  pl[37] = 2;     // pose state uncertain
  pl[38] = 200;   // quality
  pl[41] = 0xF0;  // rssi -16
  pl[42] = 0x05;  // frame id 5
  am::Packet p;
  p.header.payload_type = am::payload_type::kSensorMeasurement;
  p.payload = pl;
  const auto parsed = am::parse_packet(am::encode_packet(p));
  ASSERT_TRUE(parsed.packet);
  const auto m = std::get<am::SensorMeasurement>(*am::decode_payload(*parsed.packet).payload);
  EXPECT_TRUE(m.old_layout);
  EXPECT_NEAR(m.position_m[0], 57e-5, 1e-12);
  EXPECT_EQ(m.bfield(), am::BFieldStatus::kUncertain);
  EXPECT_EQ(m.pose_state_raw, 2);
  EXPECT_EQ(m.quality_raw, 200);
  EXPECT_EQ(m.rssi, -16);
  EXPECT_EQ(m.frame_id, 5U);
  EXPECT_FALSE(m.temperature_c.has_value());
}

TEST(Amfiprot, CommonRepliesDecode) {
  am::Packet p;
  p.header.payload_type = am::payload_type::kCommon;
  p.payload = {am::command::kReplyDeviceId, 7, 1, 0, 0, 0, 2, 0, 0, 0, 3, 0, 0, 0};
  const auto id = std::get<am::DeviceIdReply>(*am::decode_payload(p).payload);
  EXPECT_EQ(id.tx_id, 7);
  EXPECT_EQ(id.uuid[2], 3U);
  p.payload = {am::command::kReplyDeviceName, 'S', 'e', 'n', 's', 'o', 'r', 0, 'x'};
  EXPECT_EQ(std::get<am::DeviceNameReply>(*am::decode_payload(p).payload).name, "Sensor");
  p.payload = {am::command::kReplyFirmwareVersion, 1, 0, 0, 0, 2, 0, 0, 0, 3, 0, 0, 0, 4, 0, 0, 0};
  EXPECT_EQ(std::get<am::FirmwareVersionReply>(*am::decode_payload(p).payload).words[3], 4U);
  p.payload = {am::command::kReplyConfigValueUid, 0x78, 0x56, 0x34, 0x12, 3, 0xAA};
  const auto cv = std::get<am::ConfigValueReply>(*am::decode_payload(p).payload);
  EXPECT_EQ(cv.uid, 0x12345678U);
  EXPECT_EQ(cv.value, Bytes{0xAA});
  p.header.payload_type = am::payload_type::kFailure;
  EXPECT_EQ(std::get<am::StatusReply>(*am::decode_payload(p).payload).code, 0xFE);
  const auto req = am::request_config_value(3, 2, 0x12345678);
  EXPECT_EQ(req.payload, (Bytes{am::command::kRequestConfigValueUid, 0x78, 0x56, 0x34, 0x12}));
}

TEST(Amfiprot, HidReportsSkipTheUntrustedPrefix) {
  Bytes report(64, 0);
  report[0] = 0x11;  // whatever the device puts there
  report[1] = 0x99;
  std::copy(kPoseVector.begin(), kPoseVector.end(), report.begin() + 2);
  const auto parsed = am::parse_hid_report(report);
  ASSERT_TRUE(parsed.packet);
  EXPECT_EQ(parsed.packet->header.packet_number, 7);
  const auto out = am::encode_hid_report(am::request_device_id(0));
  EXPECT_EQ(out[0], 0x01);
  EXPECT_EQ(Bytes(out.begin() + 1, out.begin() + 10), kRequestDeviceIdVector);
  EXPECT_TRUE(std::all_of(out.begin() + 10, out.end(), [](uint8_t b) { return b == 0; }));
}

TEST(Amfiprot, CobsRoundTripsEveryShape) {
  std::mt19937 rng(7);
  for (size_t n : {0UL, 1UL, 2UL, 253UL, 254UL, 255UL, 300UL}) {
    for (int rep = 0; rep < 20; ++rep) {
      Bytes in(n);
      for (auto& b : in)
        b = static_cast<uint8_t>(rng() % 4 == 0 ? 0 : rng());
      const Bytes enc = am::cobs_encode(in);
      EXPECT_EQ(std::count(enc.begin(), enc.end(), 0), 0) << "no zero inside a COBS frame";
      const auto dec = am::cobs_decode(enc);
      ASSERT_TRUE(dec) << n;
      EXPECT_EQ(*dec, in);
    }
  }
  EXPECT_FALSE(am::cobs_decode(Bytes{0x05, 0x11, 0x22}).has_value()) << "truncated block";
}

TEST(Amfiprot, CobsStreamResynchronisesAfterATornFrame) {
  am::CobsStreamDecoder d;
  Bytes stream;
  auto append_frame = [&](const Bytes& pkt) {
    const Bytes enc = am::cobs_encode(pkt);
    stream.insert(stream.end(), enc.begin(), enc.end());
    stream.push_back(0);
  };
  append_frame(kPoseVector);
  // A torn frame: the first half of a packet, then the delimiter (the device reset mid-frame).
  const Bytes enc = am::cobs_encode(kPoseVector);
  stream.insert(stream.end(), enc.begin(), enc.begin() + 20);
  stream.push_back(0);
  // Line noise longer than any frame, then a delimiter.
  for (int i = 0; i < 200; ++i)
    stream.push_back(static_cast<uint8_t>(0x55 + i % 3));
  stream.push_back(0);
  append_frame(kRequestDeviceIdVector);
  // Fed in odd-sized pieces, as reads return them.
  for (size_t i = 0; i < stream.size(); i += 7) {
    d.feed(std::span(stream).subspan(i, std::min<size_t>(7, stream.size() - i)));
  }
  auto first = d.next();
  auto second = d.next();
  ASSERT_TRUE(first && second);
  EXPECT_EQ(first->header.payload_type, am::payload_type::kSensorMeasurement);
  EXPECT_EQ(second->header.destination, am::kBroadcastTxId);
  EXPECT_FALSE(d.next());
  EXPECT_EQ(d.stats().frames, 2U);
  EXPECT_EQ(d.stats().overlong, 1U);
  EXPECT_EQ(d.stats().bad_cobs + d.stats().bad_packet, 1U) << "the torn frame, counted once";
}

TEST(Amfiprot, RandomBytesNeverCrashTheDecoders) {
  std::mt19937 rng(99);
  am::CobsStreamDecoder d;
  uint64_t parsed = 0;
  for (int i = 0; i < 100000; ++i) {
    Bytes b(rng() % 70);
    for (auto& x : b)
      x = static_cast<uint8_t>(rng());
    if (i % 3 == 0 && b.size() >= 7) b[6] = am::crc8(std::span(b).first(6));  // get past the header
    const auto p = am::parse_packet(b);
    if (p.packet) {
      ++parsed;
      (void)am::decode_payload(*p.packet);
    }
    (void)am::parse_hid_report(b);
    d.feed(b);
    while (d.next()) {
    }
  }
  EXPECT_GT(parsed, 0U);
}
