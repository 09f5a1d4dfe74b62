// The HID packet link (reports -> packets), the reconnecting link (back-off, counters kept over
// reconnects) and the shell's discovery, with in-test device doubles.
#include <gtest/gtest.h>

#include <deque>

#include "amfitrack/amfitrack.hpp"
#include "amfitrack/open_link.hpp"

namespace am = amfitrack;
using namespace std::chrono_literals;
using hal::Nanos;

namespace {

// A HID device double: queued input reports, recorded output reports, unplug on demand.
class FakeHid final : public hal::HidDevice {
 public:
  std::deque<std::vector<uint8_t>> in;
  std::vector<std::vector<uint8_t>> out;
  bool unplugged = false;

  long read(std::span<uint8_t> report) override {
    if (unplugged) return -1;
    if (in.empty()) return 0;
    const auto r = in.front();
    in.pop_front();
    const size_t n = std::min(r.size(), report.size());
    std::copy_n(r.begin(), n, report.begin());
    return static_cast<long>(n);
  }
  long write(std::span<const uint8_t> report) override {
    if (unplugged) return -1;
    out.emplace_back(report.begin(), report.end());
    return static_cast<long>(report.size());
  }
  [[nodiscard]] std::string last_error() const override { return unplugged ? "gone" : ""; }
};

am::SensorMeasurement pose(uint32_t frame_id) {
  am::SensorMeasurement m;
  m.position_m = {1.0, 0.5, 0.0};
  m.quaternion_xyzw = {0, 0, 0, 1};
  m.sensor_status = 0x08;
  m.pose_state_raw = 1;
  m.quality_raw = 230;
  m.frame_id = frame_id;
  return m;
}

// An IN report as the device sends it: report id, length byte, packet, padding.
std::vector<uint8_t> in_report(const am::Packet& p) {
  std::vector<uint8_t> r(am::kHidReportSize, 0);
  const auto bytes = am::encode_packet(p);
  r[0] = 0x01;
  r[1] = static_cast<uint8_t>(bytes.size());
  std::copy(bytes.begin(), bytes.end(), r.begin() + 2);
  return r;
}

TEST(HidPacketLink, DecodesReportsCountsBadOnesAndFailsOnUnplug) {
  auto dev = std::make_unique<FakeHid>();
  FakeHid& d = *dev;
  am::HidPacketLink link(std::move(dev));
  d.in.push_back(in_report(am::sensor_measurement_packet(pose(7), 2, 1)));
  auto bad = in_report(am::sensor_measurement_packet(pose(8), 2, 2));
  bad[2 + 10] ^= 0xFF;  // payload byte: bad payload CRC
  d.in.push_back(bad);
  d.in.push_back(in_report(am::sensor_measurement_packet(pose(9), 2, 3)));

  auto p1 = link.receive();
  ASSERT_TRUE(p1);
  EXPECT_EQ(p1->header.source, 2);
  auto p2 = link.receive();  // skips the bad report
  ASSERT_TRUE(p2);
  EXPECT_EQ(p2->header.packet_number, 3);
  EXPECT_FALSE(link.receive());
  EXPECT_EQ(link.framing_stats().frames, 3U);
  EXPECT_EQ(link.framing_stats().bad_packet, 1U);
  EXPECT_EQ(
      link.framing_stats().packet_errors[static_cast<size_t>(am::PacketError::kBadPayloadCrc)], 1U);

  ASSERT_TRUE(link.send(am::request_device_id(5)));
  ASSERT_EQ(d.out.size(), 1U);
  const auto expected = am::encode_hid_report(am::request_device_id(5));
  EXPECT_EQ(d.out[0], std::vector<uint8_t>(expected.begin(), expected.end()));
  EXPECT_EQ(d.out[0][0], 0x01) << "OUT report id";

  d.unplugged = true;
  EXPECT_FALSE(link.receive());
  EXPECT_TRUE(link.failed());
  EXPECT_FALSE(link.send(am::request_device_id(6)));
}

TEST(ReconnectingLink, BacksOffThenConnectsAndReconnectsAfterUnplug) {
  int attempts = 0;
  bool available = false;
  FakeHid* current = nullptr;
  std::vector<Nanos> attempt_times;
  Nanos now{0};
  am::ReconnectingLink link(
      [&]() {
        ++attempts;
        attempt_times.push_back(now);
        am::OpenedLink o;
        if (!available) {
          o.error = "no device";
          return o;
        }
        auto dev = std::make_unique<FakeHid>();
        current = dev.get();
        o.link = std::make_unique<am::HidPacketLink>(std::move(dev));
        o.description = "fake";
        return o;
      },
      am::ReconnectConfig{100ms, 400ms});

  // Not available: attempts at 0, 100, 300, 700, 1100 ms (back-off 100, 200, 400, 400).
  for (now = 0ms; now <= 1150ms; now += 10ms)
    link.service(now);
  EXPECT_EQ(attempt_times, (std::vector<Nanos>{0ms, 100ms, 300ms, 700ms, 1100ms}));
  EXPECT_EQ(link.events().open_failures, 5U);
  EXPECT_EQ(link.events().last_error, "no device");
  EXPECT_TRUE(link.failed());
  EXPECT_FALSE(link.send(am::request_device_id(0)));

  available = true;
  for (; now <= 1600ms; now += 10ms)
    link.service(now);
  EXPECT_EQ(link.events().connects, 1U);
  ASSERT_TRUE(link.connected());
  current->in.push_back(in_report(am::sensor_measurement_packet(pose(1), 2, 1)));
  current->in.push_back({0x01, 0x00, 0x00});  // too short: counted
  EXPECT_TRUE(link.receive());
  EXPECT_FALSE(link.receive());

  current->unplugged = true;
  EXPECT_FALSE(link.receive());
  const Nanos unplug_at = now;
  link.service(now);
  EXPECT_EQ(link.events().disconnects, 1U);
  EXPECT_FALSE(link.connected());
  EXPECT_EQ(link.next_attempt(), unplug_at + 100ms) << "back-off restarts at the first retry";
  for (; now <= unplug_at + 200ms; now += 10ms)
    link.service(now);
  EXPECT_EQ(link.events().connects, 2U);
  // Counters of the first connection are kept.
  EXPECT_EQ(link.framing_stats().frames, 2U);
  EXPECT_EQ(link.framing_stats().bad_packet, 1U);
}

// A device that answers discovery requests through a loopback link.
class LoopbackLink final : public am::PacketLink {
 public:
  std::deque<am::Packet> to_host;
  std::vector<am::Packet> from_host;
  std::optional<am::Packet> receive() override {
    if (to_host.empty()) return std::nullopt;
    auto p = to_host.front();
    to_host.pop_front();
    return p;
  }
  bool send(const am::Packet& p) override {
    from_host.push_back(p);
    return true;
  }
  [[nodiscard]] bool failed() const override { return false; }
  [[nodiscard]] am::FramingStats framing_stats() const override { return {}; }
};

am::Packet reply(uint8_t source, std::vector<uint8_t> payload) {
  am::Packet p;
  p.header.payload_length = static_cast<uint8_t>(payload.size());
  p.header.ack = am::AckType::kReply;
  p.header.payload_type = am::payload_type::kCommon;
  p.header.source = source;
  p.header.destination = am::kPcTxId;
  p.payload = std::move(payload);
  return p;
}

TEST(AmfitrackShell, DiscoversDevicesAndAsksTheirNameAndFirmware) {
  LoopbackLink link;
  am::Amfitrack tracker(link, am::AmfitrackConfig{});
  tracker.poll(0ms);
  ASSERT_EQ(link.from_host.size(), 1U);
  EXPECT_EQ(link.from_host[0].header.destination, am::kBroadcastTxId);  // keep-alive / discovery

  // ReplyDeviceID from TX 1 (the source): u8 tx id + 3 x u32 uuid.
  link.to_host.push_back(
      reply(1, {am::command::kReplyDeviceId, 1, 1, 0, 0, 0, 2, 0, 0, 0, 3, 0, 0, 0}));
  tracker.poll(10ms);
  ASSERT_EQ(tracker.devices().count(1), 1U);
  EXPECT_EQ(tracker.devices().at(1).uuid, (std::array<uint32_t, 3>{1, 2, 3}));
  ASSERT_EQ(link.from_host.size(), 3U);
  EXPECT_EQ(link.from_host[1].payload[0], am::command::kRequestDeviceName);
  EXPECT_EQ(link.from_host[1].header.destination, 1);
  EXPECT_EQ(link.from_host[2].payload[0], am::command::kRequestFirmwareVersion);

  link.to_host.push_back(reply(1, {am::command::kReplyDeviceName, 'S', 'r', 'c', 0}));
  link.to_host.push_back(reply(
      1, {am::command::kReplyFirmwareVersion, 1, 0, 0, 0, 2, 0, 0, 0, 3, 0, 0, 0, 4, 0, 0, 0}));
  // The same id again does not repeat the questions.
  link.to_host.push_back(
      reply(1, {am::command::kReplyDeviceId, 1, 1, 0, 0, 0, 2, 0, 0, 0, 3, 0, 0, 0}));
  tracker.poll(20ms);
  EXPECT_EQ(tracker.devices().at(1).name, "Src");
  EXPECT_EQ(tracker.devices().at(1).firmware, "1.2.3.4");
  EXPECT_EQ(link.from_host.size(), 3U);
}

TEST(AmfitrackShell, KeepsEveryFrameOfAPollAndCountsRepeats) {
  LoopbackLink link;
  am::Amfitrack tracker(link, am::AmfitrackConfig{});
  for (uint32_t id : {10U, 11U, 11U, 13U}) {
    link.to_host.push_back(am::sensor_measurement_packet(pose(id), 2, 0));
  }
  tracker.poll(5ms);
  ASSERT_EQ(tracker.new_measurements().size(), 4U);
  EXPECT_EQ(tracker.new_measurements()[3].m.frame_id, 13U);
  EXPECT_EQ(tracker.counters().repeated_frames, 1U);
  EXPECT_EQ(tracker.counters().dropped_frames, 1U);
  tracker.poll(10ms);
  EXPECT_TRUE(tracker.new_measurements().empty());
  EXPECT_EQ(tracker.latest()->m.frame_id, 13U);
}

TEST(LinkUri, ParsesHidAndSerialAndRejectsTheRest) {
  std::string err;
  auto h = am::parse_link_uri("hid:auto", &err);
  ASSERT_TRUE(h);
  EXPECT_EQ(h->kind, am::LinkUri::Kind::kHid);
  EXPECT_EQ(am::parse_link_uri("hid:", &err)->target, "auto");
  auto s = am::parse_link_uri("serial:/dev/ttyUSB0@921600", &err);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->target, "/dev/ttyUSB0");
  EXPECT_EQ(s->baud, 921600);
  EXPECT_EQ(am::parse_link_uri("serial:/dev/ttyS1", &err)->baud, am::kDefaultBaud);
  EXPECT_FALSE(am::parse_link_uri("serial:/dev/ttyS1@fast", &err));
  EXPECT_NE(err.find("baud rate 'fast'"), std::string::npos) << err;
  EXPECT_FALSE(am::parse_link_uri("serial:", &err));
  EXPECT_FALSE(am::parse_link_uri("usb:0", &err));
  EXPECT_NE(err.find("usb:0"), std::string::npos);
}

}  // namespace
