#include <gtest/gtest.h>
#include <linux/can/error.h>

#include "hal/can/can_bus.hpp"
#include "hal/can/socketcan_bus.hpp"
#include "hal/can/virtual_can.hpp"
#include "hal/sim_clock.hpp"

using hal::CanFrame;
using namespace std::chrono_literals;

TEST(VirtualCan, EndpointsSeeEachOthersFramesButNotTheirOwn) {
  hal::SimClock clock(1s);
  hal::VirtualCanBus a("vt1", clock);
  hal::VirtualCanBus b("vt1", clock);
  hal::VirtualCanBus c("vt1", clock);
  hal::VirtualCanBus other("vt2", clock);
  ASSERT_EQ(a.send(CanFrame::standard(0x111, {1, 2})), hal::CanSendResult::kOk);
  EXPECT_FALSE(a.receive());
  EXPECT_FALSE(other.receive());
  for (auto* ep : {&b, &c}) {
    const auto f = ep->receive();
    ASSERT_TRUE(f);
    EXPECT_EQ(f->frame, CanFrame::standard(0x111, {1, 2}));
    EXPECT_EQ(f->stamp, 1s);
  }
  EXPECT_EQ(a.stats().frames_out, 1U);
  EXPECT_EQ(b.stats().frames_in, 1U);
}

TEST(VirtualCan, BusOffRefusesSendsAndReportsAnErrorFrame) {
  hal::SimClock clock;
  hal::VirtualCanBus a("vt3", clock);
  hal::VirtualCanBus b("vt3", clock);
  a.inject_bus_off(true);
  EXPECT_EQ(a.state(), hal::CanBusState::kBusOff);
  EXPECT_EQ(a.send(CanFrame::standard(0x111, {})), hal::CanSendResult::kBusOff);
  const auto err = a.receive();
  ASSERT_TRUE(err);
  EXPECT_TRUE(err->frame.error);
  EXPECT_TRUE(hal::socketcan::decode_error_frame(err->frame).bus_off);
  EXPECT_EQ(a.stats().bus_off_count, 1U);
  EXPECT_EQ(a.stats().tx_dropped, 1U);
  EXPECT_FALSE(b.receive());
  a.inject_bus_off(false);
  EXPECT_EQ(a.send(CanFrame::standard(0x111, {})), hal::CanSendResult::kOk);
}

TEST(VirtualCan, OverflowDropsOldestAndCounts) {
  hal::SimClock clock;
  hal::VirtualCanBus a("vt4", clock);
  hal::VirtualCanBus b("vt4", clock);
  for (size_t i = 0; i < hal::VirtualCanBus::kRxCapacity + 10; ++i) {
    (void)a.send(CanFrame::standard(0x100, {static_cast<uint8_t>(i)}));
  }
  EXPECT_EQ(b.stats().rx_dropped, 10U);
  EXPECT_EQ(b.receive()->frame.data[0], 10);
}

TEST(SocketCan, FrameConversionRoundTrips) {
  CanFrame f = CanFrame::standard(0x111, {0x00, 0x96, 0, 0, 0, 0, 0, 0});
  can_frame lf = hal::socketcan::to_linux(f);
  EXPECT_EQ(lf.can_id, 0x111U);
  EXPECT_EQ(lf.len, 8);
  EXPECT_EQ(hal::socketcan::from_linux(lf), f);

  CanFrame ext;
  ext.id = 0x1ABCDEF0;
  ext.extended = true;
  ext.remote = true;
  lf = hal::socketcan::to_linux(ext);
  EXPECT_EQ(lf.can_id, 0x1ABCDEF0U | CAN_EFF_FLAG | CAN_RTR_FLAG);
  EXPECT_EQ(hal::socketcan::from_linux(lf), ext);

  can_frame err{};
  err.can_id = CAN_ERR_FLAG | CAN_ERR_BUSOFF;
  err.len = 8;
  const CanFrame back = hal::socketcan::from_linux(err);
  EXPECT_TRUE(back.error);
  EXPECT_FALSE(back.extended);
  EXPECT_EQ(back.id, static_cast<uint32_t>(CAN_ERR_BUSOFF));
}

TEST(SocketCan, FiltersMatchExactStandardIds) {
  const auto filters = hal::socketcan::make_filters({0x211, 0x221});
  ASSERT_EQ(filters.size(), 2U);
  EXPECT_EQ(filters[0].can_id, 0x211U);
  EXPECT_EQ(filters[0].can_mask, CAN_SFF_MASK | CAN_EFF_FLAG);
  EXPECT_TRUE(hal::socketcan::make_filters({}).empty());
  const can_err_mask_t m = hal::socketcan::error_mask();
  EXPECT_TRUE(m & CAN_ERR_BUSOFF);
  EXPECT_TRUE(m & CAN_ERR_TX_TIMEOUT);
  EXPECT_TRUE(m & CAN_ERR_ACK);
  EXPECT_TRUE(m & CAN_ERR_RESTARTED);
  EXPECT_TRUE(m & CAN_ERR_CRTL);
  EXPECT_FALSE(m & CAN_ERR_BUSERROR) << "bus errors flood; not subscribed";
}

TEST(SocketCan, DecodesErrorFrames) {
  CanFrame f;
  f.error = true;
  f.id = CAN_ERR_CRTL | CAN_ERR_ACK;
  f.dlc = 8;
  f.data[1] = CAN_ERR_CRTL_TX_PASSIVE;
  const auto e = hal::socketcan::decode_error_frame(f);
  EXPECT_TRUE(e.passive);
  EXPECT_TRUE(e.ack);
  EXPECT_FALSE(e.bus_off);
  EXPECT_NE(e.text.find("no ACK"), std::string::npos);
  f.id = CAN_ERR_RESTARTED;
  EXPECT_TRUE(hal::socketcan::decode_error_frame(f).restarted);
  f.id = CAN_ERR_TX_TIMEOUT;
  EXPECT_TRUE(hal::socketcan::decode_error_frame(f).tx_timeout);
}

// This machine's kernel has no CAN: opening says so plainly instead of failing obscurely.
TEST(SocketCan, OpenFailureIsExplained) {
  hal::SimClock clock;
  auto r = hal::open_can("socketcan:can9", clock);
  if (r.bus) GTEST_SKIP() << "a can9 interface exists here";
  EXPECT_NE(r.error.find("socketcan:can9"), std::string::npos) << r.error;
  EXPECT_TRUE(r.error.find("no CAN support") != std::string::npos ||
              r.error.find("no such CAN interface") != std::string::npos)
      << r.error;
}

TEST(OpenCan, RejectsUnknownUris) {
  hal::SimClock clock;
  EXPECT_NE(hal::open_can("can0", clock).error.find("socketcan:<ifname>"), std::string::npos);
  EXPECT_NE(hal::open_can("usb:1", clock).error.find("unknown CAN transport"), std::string::npos);
  EXPECT_TRUE(hal::open_can("virtual:x", clock).bus);
}

TEST(CanFrame, CansendNotation) {
  EXPECT_EQ(hal::to_cansend(CanFrame::standard(0x421, {0x01})), "421#01");
  CanFrame e;
  e.error = true;
  e.id = 0x40;
  e.dlc = 8;
  EXPECT_EQ(hal::to_cansend(e), "20000040#0000000000000000");
}
