// UDP receiver over loopback (timestamps, truncation, kernel drops) and pcap files (the real
// VLP-16 captures, write/read round trip, frame parsing).
#include <gtest/gtest.h>
#include <pcap/pcap.h>
#include <poll.h>

#include <cstdio>

#include "hal/capture/pcap_file.hpp"
#include "hal/kernel_stamp.hpp"
#include "hal/linux_clock.hpp"
#include "hal/net/udp_socket.hpp"

using namespace std::chrono_literals;

namespace {

bool wait_readable(int fd) {
  pollfd p{fd, POLLIN, 0};
  return poll(&p, 1, 2000) == 1;
}

TEST(UdpEndpoint, Parses) {
  hal::UdpEndpoint e;
  std::string err;
  ASSERT_TRUE(hal::parse_udp_endpoint("udp:0.0.0.0:2368", e, err)) << err;
  EXPECT_EQ(e.address, "0.0.0.0");
  EXPECT_EQ(e.port, 2368);
  EXPECT_FALSE(hal::parse_udp_endpoint("udp:0.0.0.0", e, err));
  EXPECT_FALSE(hal::parse_udp_endpoint("udp:1.2.3:80", e, err));
  EXPECT_NE(err.find("not an IPv4 address"), std::string::npos) << err;
  EXPECT_FALSE(hal::parse_udp_endpoint("udp:1.2.3.4:70000", e, err));
}

TEST(UdpReceiver, ReceivesWithKernelStampsAndSource) {
  auto opened = hal::UdpReceiver::open({"127.0.0.1", 0});
  ASSERT_TRUE(opened.receiver) << opened.error;
  auto& rx = *opened.receiver;
  ASSERT_NE(rx.port(), 0);
  std::string err;
  auto tx = hal::UdpSender::open(err);
  ASSERT_TRUE(tx) << err;
  hal::LinuxClock clock;
  const hal::Nanos before = clock.now();
  for (uint8_t i = 0; i < 3; ++i) {
    const std::vector<uint8_t> payload(1206, i);
    ASSERT_TRUE(tx->send_to({"127.0.0.1", rx.port()}, payload));
  }
  ASSERT_TRUE(wait_readable(rx.fd()));
  const hal::Nanos now = clock.now();
  std::vector<std::vector<uint8_t>> got;
  rx.drain(10, now, [&](const hal::UdpDatagram& d) {
    got.emplace_back(d.bytes.begin(), d.bytes.end());
    EXPECT_GE(d.stamp, before - 1ms);
    EXPECT_LE(d.stamp, now);
    EXPECT_EQ(d.source_ipv4, 0x7F000001U);
  });
  ASSERT_EQ(got.size(), 3U);
  EXPECT_EQ(got[2], std::vector<uint8_t>(1206, 2));
  EXPECT_EQ(rx.stats().datagrams, 3U);
  EXPECT_EQ(rx.stats().bytes, 3U * 1206U);
  EXPECT_EQ(rx.drain(10, now, [](const hal::UdpDatagram&) {}), 0U) << "non-blocking when empty";
}

namespace {
// The monotonic clock minus the realtime clock, from readings less than 50 us apart (retried
// until they are: a preemption between them would skew it).
hal::Nanos monotonic_minus_realtime() {
  auto read = [](clockid_t id) {
    timespec ts{};
    clock_gettime(id, &ts);
    return hal::Nanos(static_cast<int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec);
  };
  for (;;) {
    const hal::Nanos m0 = read(CLOCK_MONOTONIC);
    const hal::Nanos r = read(CLOCK_REALTIME);
    const hal::Nanos m1 = read(CLOCK_MONOTONIC);
    if (m1 - m0 < 50us) return m0 + (m1 - m0) / 2 - r;
  }
}
}  // namespace

TEST(KernelStamp, IsTheArrivalTimeEvenWhenTheCallersNowIsOld) {
  // The caller took `now` 20 ms ago (then drained a long queue, or was preempted: CI saw 3 ms on
  // a loaded machine). A datagram that arrived 30 ms ago is stamped 30 ms ago, not 50; one that
  // arrived 5 ms ago, after `now`, is stamped `now`.
  hal::LinuxClock clock;
  const hal::Nanos offset = monotonic_minus_realtime();
  const hal::Nanos mono = clock.now();
  const hal::Nanos caller_now = mono - 20ms;
  const hal::Nanos arrived_30ms_ago = mono - 30ms;
  const hal::Nanos stamp = hal::monotonic_from_kernel_stamp(arrived_30ms_ago - offset, caller_now);
  EXPECT_NEAR(static_cast<double>((stamp - arrived_30ms_ago).count()), 0.0, 1e6) << "within 1 ms";
  EXPECT_EQ(hal::monotonic_from_kernel_stamp(mono - 5ms - offset, caller_now), caller_now);
  // On a simulated clock (`now` not monotonic time) the age is taken as it is; a wall-clock jump
  // (an age of minutes, or negative) leaves `now`.
  const hal::Nanos sim_now = 5s;
  const hal::Nanos aged = hal::monotonic_from_kernel_stamp(mono - 30ms - offset, sim_now);
  EXPECT_LE(aged, sim_now - 30ms);
  EXPECT_GT(aged, sim_now - 100ms);
  EXPECT_EQ(hal::monotonic_from_kernel_stamp(mono - 120s - offset, sim_now), sim_now);
  EXPECT_EQ(hal::monotonic_from_kernel_stamp(mono + 10s - offset, sim_now), sim_now);
}

TEST(UdpReceiver, OnASimulatedClockDatagramsTakeTheDrainsTime) {
  // The kernel stamp is aged back from `now` by the wall time the datagram waited: right on the
  // robot, wrong on a simulated clock, where `now` is not the wall clock's (a loaded machine
  // aged a test's scans into 'lidar silent'). kDrain stamps with `now` itself.
  auto kernel = hal::UdpReceiver::open({"127.0.0.1", 0});
  auto drain = hal::UdpReceiver::open({"127.0.0.1", 0}, 4 << 20, hal::UdpStamp::kDrain);
  ASSERT_TRUE(kernel.receiver && drain.receiver);
  std::string err;
  auto tx = hal::UdpSender::open(err);
  ASSERT_TRUE(tx) << err;
  const std::vector<uint8_t> payload(100, 7);
  ASSERT_TRUE(tx->send_to({"127.0.0.1", kernel.receiver->port()}, payload));
  ASSERT_TRUE(tx->send_to({"127.0.0.1", drain.receiver->port()}, payload));
  ASSERT_TRUE(wait_readable(kernel.receiver->fd()));
  ASSERT_TRUE(wait_readable(drain.receiver->fd()));
  const hal::Nanos sim_now = 5s;  // a simulated clock's time, far from the wall clock's
  std::vector<hal::Nanos> kernel_stamps, drain_stamps;
  kernel.receiver->drain(10, sim_now,
                         [&](const hal::UdpDatagram& d) { kernel_stamps.push_back(d.stamp); });
  drain.receiver->drain(10, sim_now,
                        [&](const hal::UdpDatagram& d) { drain_stamps.push_back(d.stamp); });
  ASSERT_EQ(kernel_stamps.size(), 1U);
  ASSERT_EQ(drain_stamps.size(), 1U);
  EXPECT_LT(kernel_stamps[0], sim_now) << "aged by the wall time it waited";
  EXPECT_EQ(drain_stamps[0], sim_now);
}

TEST(UdpReceiver, CountsTruncatedAndKernelDrops) {
  auto opened = hal::UdpReceiver::open({"127.0.0.1", 0}, 4096);  // tiny queue on purpose
  ASSERT_TRUE(opened.receiver) << opened.error;
  auto& rx = *opened.receiver;
  std::string err;
  auto tx = hal::UdpSender::open(err);
  ASSERT_TRUE(tx);
  ASSERT_TRUE(tx->send_to({"127.0.0.1", rx.port()}, std::vector<uint8_t>(3000, 1)));
  ASSERT_TRUE(wait_readable(rx.fd()));
  rx.drain(1, 0ns, [](const hal::UdpDatagram&) { FAIL() << "a truncated datagram is dropped"; });
  EXPECT_EQ(rx.stats().truncated, 1U);
  // 100 datagrams into a queue that holds a few: loopback delivers synchronously, so every one
  // is either queued or counted by the kernel as dropped.
  for (int i = 0; i < 100; ++i) {
    ASSERT_TRUE(tx->send_to({"127.0.0.1", rx.port()}, std::vector<uint8_t>(1206, 7)));
  }
  size_t received = 0;
  while (rx.drain(100, 0ns, [&](const hal::UdpDatagram&) { ++received; }) > 0) {
  }
  // The kernel reports its drop count with the next datagram it queues.
  ASSERT_TRUE(tx->send_to({"127.0.0.1", rx.port()}, std::vector<uint8_t>(10, 8)));
  ASSERT_TRUE(wait_readable(rx.fd()));
  rx.drain(1, 0ns, [&](const hal::UdpDatagram&) { ++received; });
  EXPECT_GT(rx.stats().kernel_drops, 0U);
  EXPECT_EQ(received + rx.stats().kernel_drops, 101U);
}

TEST(UdpReceiver, BindErrorNamesTheEndpoint) {
  auto a = hal::UdpReceiver::open({"127.0.0.1", 0});
  ASSERT_TRUE(a.receiver);
  auto b = hal::UdpReceiver::open({"192.0.2.1", 2368});  // not an address of this machine
  ASSERT_FALSE(b.receiver);
  EXPECT_NE(b.error.find("192.0.2.1:2368"), std::string::npos) << b.error;
}

TEST(Pcap, ReadsTheRealVlp16Captures) {
  std::string err;
  auto r = hal::PcapReader::open(COMPANION_TEST_DATA "/vlp16/vlp16_2014_strongest.pcap", err);
  ASSERT_TRUE(r) << err;
  EXPECT_EQ(r->link_type(), DLT_EN10MB);
  auto first = r->next(2368);
  ASSERT_TRUE(first);
  EXPECT_EQ(first->payload.size(), 1206U);
  EXPECT_EQ(first->source_ipv4, 0xC0A801C8U);  // 192.168.1.200
  EXPECT_EQ(first->capture_time, std::chrono::seconds(1415644617) + 383637us);
  size_t data = 1;
  while (auto p = r->next(2368)) {
    EXPECT_EQ(p->payload.size(), 1206U);
    ++data;
  }
  EXPECT_EQ(data, 84U);
  EXPECT_EQ(r->stats().other_port, 16U) << "the position packets on 8308";
  EXPECT_EQ(r->stats().malformed, 0U);

  auto pos = hal::PcapReader::open(COMPANION_TEST_DATA "/vlp16/vlp16_2014_strongest.pcap", err);
  size_t position = 0;
  while (auto p = pos->next(8308)) {
    EXPECT_EQ(p->payload.size(), 512U);
    ++position;
  }
  EXPECT_EQ(position, 16U);
}

TEST(Pcap, WriteThenReadRoundTrips) {
  const std::string path = ::testing::TempDir() + "roundtrip.pcap";
  std::string err;
  {
    auto w = hal::PcapWriter::open(path, err);
    ASSERT_TRUE(w) << err;
    for (uint8_t i = 0; i < 3; ++i) {
      hal::PcapUdpPacket p;
      p.capture_time = std::chrono::seconds(1700000000) + std::chrono::microseconds(1327 * i);
      p.source_ipv4 = 0xC0A801C9;
      p.destination_ipv4 = 0xFFFFFFFF;
      p.source_port = 2368;
      p.destination_port = 2368;
      p.payload.assign(1206, i);
      w->write(p);
    }
  }
  auto r = hal::PcapReader::open(path, err);
  ASSERT_TRUE(r) << err;
  for (uint8_t i = 0; i < 3; ++i) {
    auto p = r->next(2368);
    ASSERT_TRUE(p);
    EXPECT_EQ(p->payload, std::vector<uint8_t>(1206, i));
    EXPECT_EQ(p->capture_time,
              std::chrono::seconds(1700000000) + std::chrono::microseconds(1327 * i));
    EXPECT_EQ(p->source_ipv4, 0xC0A801C9U);
  }
  EXPECT_FALSE(r->next());
  (void)std::remove(path.c_str());
}

TEST(Pcap, FrameParsingHandlesVlanCookedFragmentsAndGarbage) {
  hal::PcapUdpPacket src;
  src.source_port = 2368;
  src.destination_port = 2368;
  src.payload = {1, 2, 3};
  const auto frame = hal::build_udp_frame(src);
  hal::PcapUdpPacket out;
  ASSERT_EQ(hal::parse_udp_frame(DLT_EN10MB, frame, out), hal::FrameParse::kUdp);
  EXPECT_EQ(out.payload, src.payload);

  auto vlan = frame;  // insert an 802.1Q tag after the MAC addresses
  vlan.insert(vlan.begin() + 12, {0x81, 0x00, 0x00, 0x05});
  ASSERT_EQ(hal::parse_udp_frame(DLT_EN10MB, vlan, out), hal::FrameParse::kUdp);
  EXPECT_EQ(out.payload, src.payload);

  std::vector<uint8_t> sll(16, 0);  // Linux cooked header: protocol at 14
  sll[14] = 0x08;
  sll.insert(sll.end(), frame.begin() + 14, frame.end());
  ASSERT_EQ(hal::parse_udp_frame(DLT_LINUX_SLL, sll, out), hal::FrameParse::kUdp);

  auto frag = frame;
  frag[14 + 6] = 0x20;  // more fragments
  EXPECT_EQ(hal::parse_udp_frame(DLT_EN10MB, frag, out), hal::FrameParse::kFragment);
  auto tcp = frame;
  tcp[14 + 9] = 6;
  EXPECT_EQ(hal::parse_udp_frame(DLT_EN10MB, tcp, out), hal::FrameParse::kNotUdp);
  for (size_t cut = 0; cut < frame.size(); ++cut) {
    EXPECT_EQ(hal::parse_udp_frame(DLT_EN10MB, std::span(frame.data(), cut), out),
              hal::FrameParse::kMalformed)
        << cut;
  }
  auto bad_len = frame;
  bad_len[14 + 20 + 5] = 200;  // UDP length beyond the IP packet
  EXPECT_EQ(hal::parse_udp_frame(DLT_EN10MB, bad_len, out), hal::FrameParse::kMalformed);
}

TEST(Pcap, MissingFileIsAClearError) {
  std::string err;
  EXPECT_FALSE(hal::PcapReader::open("/nonexistent/x.pcap", err));
  EXPECT_NE(err.find("/nonexistent/x.pcap"), std::string::npos) << err;
}

}  // namespace
