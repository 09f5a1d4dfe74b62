#include <gtest/gtest.h>
#include <poll.h>
#include <pty.h>
#include <unistd.h>

#include <string>

#include "hal/can/slcan_bus.hpp"
#include "hal/can/slcan_codec.hpp"
#include "hal/sim_clock.hpp"

using hal::CanFrame;
namespace slcan = hal::slcan;
using namespace std::chrono_literals;

// The reference's example `t1118009600000000000` has 15 data digits for 8 bytes (a typo: one
// '0' missing); 0x111 with 00 96 00 00 00 00 00 00 is t111 8 0096000000000000.
TEST(SlcanCodec, EncodesTheReferenceExample) {
  EXPECT_EQ(slcan::encode(CanFrame::standard(0x111, {0x00, 0x96, 0, 0, 0, 0, 0, 0})),
            "t11180096000000000000\r");
  slcan::Parser typo;
  typo.feed("t1118009600000000000\r");
  EXPECT_FALSE(typo.next_frame()) << "15 digits for 8 bytes is malformed";
  EXPECT_EQ(typo.stats().malformed, 1U);
  CanFrame ext;
  ext.id = 0x12345678;
  ext.extended = true;
  ext.dlc = 2;
  ext.data[0] = 0xDE;
  ext.data[1] = 0xAD;
  EXPECT_EQ(slcan::encode(ext), "T123456782DEAD\r");
  CanFrame rtr;
  rtr.id = 0x421;
  rtr.remote = true;
  rtr.dlc = 1;
  EXPECT_EQ(slcan::encode(rtr), "r4211\r");
  CanFrame err;
  err.error = true;
  EXPECT_FALSE(slcan::encode(err).has_value());
  EXPECT_EQ(slcan::bitrate_command(500), "S6");
  EXPECT_EQ(slcan::bitrate_command(1000), "S8");
  EXPECT_FALSE(slcan::bitrate_command(300).has_value());
}

TEST(SlcanCodec, ParserDecodesFramesRepliesAndTimestamps) {
  slcan::Parser p;
  p.feed("t11180096000000000000\r\rz\r\aT123456782DEAD\rt2210\rt22120102ABCD\r");
  auto f = p.next_frame();
  ASSERT_TRUE(f);
  EXPECT_EQ(*f, CanFrame::standard(0x111, {0x00, 0x96, 0, 0, 0, 0, 0, 0}));
  f = p.next_frame();
  ASSERT_TRUE(f);
  EXPECT_TRUE(f->extended);
  EXPECT_EQ(f->id, 0x12345678U);
  f = p.next_frame();
  ASSERT_TRUE(f);
  EXPECT_EQ(f->dlc, 0);
  f = p.next_frame();
  ASSERT_TRUE(f) << "4-digit timestamp (Z1) after the data is accepted";
  EXPECT_EQ(f->dlc, 2);
  EXPECT_EQ(f->data[1], 0x02);
  EXPECT_FALSE(p.next_frame());
  EXPECT_EQ(p.stats().acks, 2U);
  EXPECT_EQ(p.stats().nacks, 1U);
}

TEST(SlcanCodec, ParserResynchronisesAfterGarbage) {
  slcan::Parser p;
  p.feed("t11180096\rxyz\rt1119" + std::string(200, 'Q') + "\rt1110\r");
  p.feed("t11");  // a frame split across reads
  p.feed("12AABB\r");
  int frames = 0;
  while (auto f = p.next_frame()) {
    ++frames;
    EXPECT_EQ(f->id, 0x111U);
  }
  EXPECT_EQ(frames, 2);
  EXPECT_EQ(p.stats().malformed, 2U) << "short data and 'xyz'";
  EXPECT_EQ(p.stats().overlong, 1U);
}

TEST(SlcanCodec, RandomBytesNeverCrashTheParser) {
  slcan::Parser p;
  uint32_t x = 12345;
  std::string junk;
  for (int i = 0; i < 200000; ++i) {
    x = x * 1103515245 + 12345;
    junk.push_back(static_cast<char>((x >> 16) & 0xFF));
  }
  p.feed(junk);
  while (auto f = p.next_frame())
    ASSERT_LE(f->dlc, 8);
  p.feed("\rt1110\r");  // the next CR ends whatever the junk left half-read
  bool found = false;
  while (auto f = p.next_frame())
    found = f->id == 0x111;
  EXPECT_TRUE(found) << "still decodes after random input";
}

namespace {
// The adapter's side of a pseudo-terminal: reads what the host writes, writes what a CAN bus
// would deliver. Waits with poll(), never sleeps.
class SlcanPeer {
 public:
  SlcanPeer() {
    char name[256];
    ok_ = openpty(&master_, &slave_, name, nullptr, nullptr) == 0;
    path_ = name;
  }
  ~SlcanPeer() {
    close(master_);
    close(slave_);
  }
  [[nodiscard]] bool ok() const { return ok_; }
  [[nodiscard]] const std::string& path() const { return path_; }
  // Reads until `needle` has been seen (or 2 s pass); returns everything read.
  std::string read_until(const std::string& needle) {
    for (;;) {
      if (buf_.find(needle) != std::string::npos) return buf_;
      pollfd p{master_, POLLIN, 0};
      if (poll(&p, 1, 2000) <= 0) return buf_;
      char tmp[256];
      const ssize_t n = read(master_, tmp, sizeof(tmp));
      if (n <= 0) return buf_;
      buf_.append(tmp, static_cast<size_t>(n));
    }
  }
  void write_text(const std::string& s) {
    ASSERT_EQ(write(master_, s.data(), s.size()), static_cast<ssize_t>(s.size()));
  }
  // Waits until the host side has bytes to read.
  bool wait_host_readable() {
    pollfd p{slave_, POLLIN, 0};
    return poll(&p, 1, 2000) > 0;
  }

 private:
  int master_ = -1;
  int slave_ = -1;
  std::string path_;
  std::string buf_;
  bool ok_ = false;
};
}  // namespace

TEST(SlcanBus, OpensSendsAndReceivesOverAPseudoTerminal) {
  SlcanPeer peer;
  ASSERT_TRUE(peer.ok());
  hal::SimClock clock(42s);
  auto opened = hal::SlcanBus::open(peer.path(), 115200, 500, clock);
  ASSERT_TRUE(opened.bus) << opened.error;
  // Open sequence: close, 500 kbit/s, open; no reply needed (this adapter never answers).
  EXPECT_NE(peer.read_until("O\r").find("C\rS6\rO\r"), std::string::npos);

  EXPECT_EQ(opened.bus->send(CanFrame::standard(0x111, {0x00, 0x96, 0, 0, 0, 0, 0, 0})),
            hal::CanSendResult::kOk);
  EXPECT_NE(peer.read_until("t11180096000000000000\r").find("t11180096000000000000\r"),
            std::string::npos);

  peer.write_text("\rt2218FF6A00000000C800\r");
  ASSERT_TRUE(peer.wait_host_readable());
  std::optional<hal::StampedCanFrame> got;
  for (int i = 0; i < 1000 && !got; ++i)
    got = opened.bus->receive();
  ASSERT_TRUE(got);
  EXPECT_EQ(got->frame.id, 0x221U);
  EXPECT_EQ(got->frame.data[0], 0xFF);
  EXPECT_EQ(got->stamp, 42s) << "stamped on the given clock";
  EXPECT_EQ(opened.bus->stats().frames_in, 1U);
  EXPECT_EQ(opened.bus->stats().frames_out, 1U);
}

TEST(SlcanBus, MissingDeviceIsAClearError) {
  hal::SimClock clock;
  auto opened = hal::SlcanBus::open("/dev/does-not-exist", 115200, 500, clock);
  EXPECT_FALSE(opened.bus);
  EXPECT_NE(opened.error.find("/dev/does-not-exist"), std::string::npos) << opened.error;
}
