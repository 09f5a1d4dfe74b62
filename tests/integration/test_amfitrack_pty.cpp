// The Amfitrack shell over a serial link on a pseudo-terminal: an emulated device streams
// COBS-framed 0x1A frames at 120 Hz (simulated time); the shell reads them through the real
// serial port code, measures the rate, counts a dropped frame, and the gate trips and recovers.
#include <gtest/gtest.h>
#include <poll.h>
#include <pty.h>
#include <unistd.h>

#include "amfitrack/amfitrack.hpp"
#include "hal/serial_port.hpp"
#include "hal/sim_clock.hpp"

namespace am = amfitrack;
using namespace std::chrono_literals;
using hal::Nanos;

namespace {

class EmulatedDevice {
 public:
  EmulatedDevice() {
    char name[256];
    ok_ = openpty(&master_, &slave_, name, nullptr, nullptr) == 0;
    path_ = name;
  }
  ~EmulatedDevice() {
    close(master_);
    close(slave_);
  }
  [[nodiscard]] bool ok() const { return ok_; }
  [[nodiscard]] const std::string& path() const { return path_; }

  // Writes one pose frame and waits until the host side can read it.
  void send_pose(uint32_t frame_id, uint8_t quality, uint8_t pose_state = 1, uint8_t tx = 2) {
    am::SensorMeasurement m;
    m.position_m = {1.2, -0.3, 0.1};
    m.quaternion_xyzw = {0, 0, 0, 1};
    m.sensor_status = 0x08;
    m.pose_state_raw = pose_state;
    m.quality_raw = quality;
    m.frame_id = frame_id & 0xFFFFFF;
    auto frame =
        am::cobs_encode(am::encode_packet(am::sensor_measurement_packet(m, tx, number_++)));
    frame.push_back(0);
    ASSERT_EQ(write(master_, frame.data(), frame.size()), static_cast<ssize_t>(frame.size()));
    pollfd p{slave_, POLLIN, 0};
    ASSERT_EQ(poll(&p, 1, 2000), 1);
  }
  // Packets the host sent to the device.
  std::vector<am::Packet> host_packets() {
    pollfd p{master_, POLLIN, 0};
    uint8_t buf[512];
    while (poll(&p, 1, 0) == 1) {
      const ssize_t n = read(master_, buf, sizeof(buf));
      if (n <= 0) break;
      decoder_.feed(std::span<const uint8_t>(buf, static_cast<size_t>(n)));
    }
    std::vector<am::Packet> out;
    while (auto pk = decoder_.next())
      out.push_back(*pk);
    return out;
  }

 private:
  int master_ = -1;
  int slave_ = -1;
  std::string path_;
  bool ok_ = false;
  uint8_t number_ = 0;
  am::CobsStreamDecoder decoder_;
};

}  // namespace

TEST(AmfitrackPty, StreamsMeasuresDropsAndGates) {
  EmulatedDevice dev;
  ASSERT_TRUE(dev.ok());
  auto port = hal::open_serial(dev.path(), 115200);
  ASSERT_TRUE(port.port) << port.error;
  EXPECT_EQ(port.port->backend(), "termios");
  am::SerialCobsLink link(std::move(port.port));
  am::Amfitrack tracker(link, am::AmfitrackConfig{});
  hal::SimClock clock(5s);
  const Nanos period(8'333'333);

  uint32_t id = 100;
  auto tick = [&](uint8_t quality, uint8_t pose_state = 1) {
    dev.send_pose(id++, quality, pose_state);
    clock.advance_by(period);
    tracker.poll(clock.now());
    return tracker.confidence(clock.now());
  };

  // One second of good frames: ~120 Hz measured, GOOD after the recovery streak.
  am::GateOutput out;
  for (int i = 0; i < 120; ++i)
    out = tick(230);
  EXPECT_EQ(out.confidence, am::Confidence::kGood);
  EXPECT_NEAR(tracker.rate_hz(), 120.0, 1.0);
  EXPECT_EQ(tracker.counters().poses, 120U);
  ASSERT_TRUE(tracker.latest());
  EXPECT_NEAR(tracker.latest()->m.position_m[0], 1.2, 1e-9);
  EXPECT_EQ(tracker.latest()->stamp, clock.now()) << "stamped at reception";

  // A frame lost on the radio: the id gap is counted, the rate stays 120 Hz.
  ++id;
  clock.advance_by(period);  // the lost frame's slot passes
  out = tick(230);
  EXPECT_EQ(tracker.counters().dropped_frames, 1U);
  EXPECT_NEAR(tracker.rate_hz(), 120.0, 1.0);

  // Quality drops: BAD within one frame; back to GOOD only after the hysteresis.
  out = tick(60);
  EXPECT_EQ(out.confidence, am::Confidence::kBad);
  EXPECT_EQ(out.reason, am::GateReason::kQualityLow);
  for (int i = 0; i < 11; ++i)
    out = tick(230);
  EXPECT_EQ(out.confidence, am::Confidence::kBad) << "recovering";
  out = tick(230);
  EXPECT_EQ(out.confidence, am::Confidence::kGood);

  // Tracking lost: BAD at once.
  out = tick(230, 0);
  EXPECT_EQ(out.reason, am::GateReason::kPoseNotTracking);

  // Frames from another sensor are ignored; silence makes the data stale.
  dev.send_pose(id++, 230, 1, /*tx=*/9);
  clock.advance_by(60ms);
  tracker.poll(clock.now());
  EXPECT_EQ(tracker.counters().poses_other_sensor, 1U);
  EXPECT_EQ(tracker.confidence(clock.now()).reason, am::GateReason::kStale);

  // The keep-alive reached the device: RequestDeviceID broadcast.
  const auto sent = dev.host_packets();
  ASSERT_FALSE(sent.empty());
  EXPECT_EQ(sent[0].header.destination, am::kBroadcastTxId);
  EXPECT_EQ(sent[0].payload, std::vector<uint8_t>{am::command::kRequestDeviceId});
  EXPECT_GE(tracker.counters().keepalives_sent, 1U);
}
