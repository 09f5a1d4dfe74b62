// Taps of `companiond --record`: traffic passes unchanged and lands in files other tools read.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>

#include "hal/can/virtual_can.hpp"
#include "hal/capture/recorders.hpp"
#include "hal/net/datagram_queue.hpp"
#include "hal/sim_clock.hpp"

using namespace std::chrono_literals;

TEST(RecordingCanBus, PassesFramesAndLogsBothDirectionsAsCandump) {
  hal::SimClock clock(5s);
  const std::string path = ::testing::TempDir() + "rec.candump";
  auto peer = std::make_unique<hal::VirtualCanBus>("rec-test", clock);
  {
    hal::RecordingCanBus bus(std::make_unique<hal::VirtualCanBus>("rec-test", clock), path, "can0",
                             clock);
    ASSERT_TRUE(bus.ok());
    hal::CanFrame out;
    out.id = 0x111;
    out.dlc = 8;
    out.data = {0x00, 0x96, 0, 0, 0, 0, 0, 0};
    ASSERT_EQ(bus.send(out), hal::CanSendResult::kOk);
    const auto at_peer = peer->receive();
    ASSERT_TRUE(at_peer);
    EXPECT_EQ(at_peer->frame.data, out.data) << "passed through unchanged";
    hal::CanFrame in;
    in.id = 0x211;
    in.dlc = 2;
    in.data = {0x01, 0x02};
    ASSERT_EQ(peer->send(in), hal::CanSendResult::kOk);
    const auto got = bus.receive();
    ASSERT_TRUE(got);
    EXPECT_EQ(got->frame.id, 0x211U);
    EXPECT_EQ(bus.stats().frames_out, 1U);
  }
  hal::CandumpReader reader(path);
  const auto first = reader.next();
  const auto second = reader.next();
  ASSERT_TRUE(first && second);
  EXPECT_EQ(first->frame.id, 0x111U) << "sent";
  EXPECT_EQ(first->frame.data[1], 0x96);
  EXPECT_EQ(second->frame.id, 0x211U) << "received";
  EXPECT_EQ(second->frame.dlc, 2);
  EXPECT_FALSE(reader.next());
}

TEST(RecordingCanBus, TheLogReadsBackWithWallClockTimes) {
  hal::SimClock clock(5s);
  const std::string path = ::testing::TempDir() + "rec2.candump";
  {
    hal::RecordingCanBus bus(std::make_unique<hal::VirtualCanBus>("rec-test2", clock), path, "can0",
                             clock);
    hal::CanFrame f;
    f.id = 0x421;
    f.dlc = 1;
    f.data[0] = 0x01;
    ASSERT_EQ(bus.send(f), hal::CanSendResult::kOk);
  }
  hal::CandumpReader reader(path);
  const auto rec = reader.next();
  ASSERT_TRUE(rec);
  EXPECT_EQ(rec->iface, "can0");
  EXPECT_EQ(rec->frame.id, 0x421U);
  EXPECT_EQ(rec->frame.data[0], 0x01);
  EXPECT_GT(rec->sec, 1'600'000'000) << "wall clock (Unix time), as candump writes";
}

TEST(RecordingDatagramSource, PassesDatagramsAndWritesAPcapThatReadsBack) {
  const std::string path = ::testing::TempDir() + "rec.pcap";
  auto queue = std::make_unique<hal::DatagramQueue>();
  hal::DatagramQueue* q = queue.get();
  std::string error;
  auto writer = hal::PcapWriter::open(path, error);
  ASSERT_TRUE(writer) << error;
  {
    hal::RecordingDatagramSource src(std::move(queue), std::move(writer), 2368);
    const std::array<uint8_t, 3> bytes{7, 8, 9};
    q->push(bytes, hal::Nanos(1000));
    int seen = 0;
    src.drain(10, hal::Nanos(2000), [&](const hal::UdpDatagram& d) {
      EXPECT_EQ(d.bytes.size(), 3U);
      EXPECT_EQ(d.bytes[2], 9);
      ++seen;
    });
    EXPECT_EQ(seen, 1);
  }
  auto reader = hal::PcapReader::open(path, error);
  ASSERT_TRUE(reader) << error;
  const auto p = reader->next(2368);
  ASSERT_TRUE(p);
  EXPECT_EQ(p->payload, (std::vector<uint8_t>{7, 8, 9}));
  EXPECT_EQ(p->destination_port, 2368);
  EXPECT_FALSE(reader->next(2368));
}
