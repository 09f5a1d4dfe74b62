// The driver's per-id reception rate (what candiag shows) under an irregular arrival pattern:
// frames stamped by the in-process bus on a simulated clock.
#include <gtest/gtest.h>

#include "hal/can/virtual_can.hpp"
#include "hal/sim_clock.hpp"
#include "scout_mini/scout_codec.hpp"
#include "scout_mini/scout_mini.hpp"

using namespace std::chrono_literals;

namespace {

struct Rig {
  hal::SimClock clock{1s};
  hal::VirtualCanBus base_end{"id-stats", clock};
  hal::VirtualCanBus host_end{"id-stats", clock};
  scout_mini::ScoutMini driver{host_end, {}};

  void send_motion_after(hal::Nanos gap) {
    clock.advance_by(gap);
    ASSERT_EQ(base_end.send(scout_mini::encode(scout_mini::MotionState{})),
              hal::CanSendResult::kOk);
    driver.poll(clock.now());
  }
};

}  // namespace

TEST(ScoutIdStats, RateOfARegularStreamIsItsFrequency) {
  Rig rig;
  for (int i = 0; i < 100; ++i)
    rig.send_motion_after(20ms);
  const scout_mini::IdStats& s = rig.driver.id_stats(0x221);
  EXPECT_EQ(s.count, 100U);
  EXPECT_NEAR(s.rate_hz(), 50.0, 1e-6);
}

// 50 frames a second on average, arriving 5 ms and 35 ms apart in turn (a jittery adapter or a
// loaded host). Averaging the instantaneous frequencies (200 Hz and 28.6 Hz) reads over 100 Hz;
// the rate must be the stream's: frames over time.
TEST(ScoutIdStats, JitterDoesNotInflateTheRate) {
  Rig rig;
  for (int i = 0; i < 200; ++i)
    rig.send_motion_after(i % 2 == 0 ? 5ms : 35ms);
  const scout_mini::IdStats& s = rig.driver.id_stats(0x221);
  EXPECT_EQ(s.count, 200U);
  EXPECT_NEAR(s.rate_hz(), 50.0, 4.0);
}

TEST(ScoutIdStats, NoRateBeforeTheSecondFrame) {
  Rig rig;
  EXPECT_EQ(rig.driver.id_stats(0x221).rate_hz(), 0.0);
  rig.send_motion_after(20ms);
  EXPECT_EQ(rig.driver.id_stats(0x221).count, 1U);
  EXPECT_EQ(rig.driver.id_stats(0x221).rate_hz(), 0.0);
  rig.send_motion_after(10ms);
  EXPECT_NEAR(rig.driver.id_stats(0x221).rate_hz(), 100.0, 1e-6);
}
