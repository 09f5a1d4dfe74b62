// The Scout Mini driver against the simulated base, over the in-process virtual bus and over
// slcan on a pseudo-terminal: both ends speak real frames, time is simulated (100 Hz loop).
#include <gtest/gtest.h>
#include <pty.h>
#include <unistd.h>

#include <cmath>
#include <functional>
#include <memory>

#include "hal/can/slcan_bus.hpp"
#include "hal/can/virtual_can.hpp"
#include "hal/serial_port.hpp"
#include "hal/sim_clock.hpp"
#include "scout_mini/scout_mini.hpp"
#include "sim/sim_scout_mini.hpp"

using namespace std::chrono_literals;
using scout_mini::ControlMode;

namespace {

struct Command {
  double vx = 0, vy = 0, wz = 0;
  bool send = true;  // false: the driver goes silent (no 0x111 at all)
};

using BusPair = std::pair<std::unique_ptr<hal::CanBus>, std::unique_ptr<hal::CanBus>>;

// Host and base on two ends of one link; run() steps both at 100 Hz on a simulated clock.
class Rig {
 public:
  explicit Rig(const std::function<BusPair(hal::Clock&)>& make)
      : buses(make(clock)), base(*buses.second), driver(*buses.first, {}) {}

  void run(hal::Nanos duration, const Command& cmd = {}) {
    const hal::Nanos end = clock.now() + duration;
    while (clock.now() < end) {
      tick(cmd);
    }
  }
  void tick(const Command& cmd) {
    const hal::Nanos now = clock.now();
    base.step(now);
    driver.poll(now);
    if (cmd.send) driver.command(cmd.vx, cmd.vy, cmd.wz, now);
    clock.advance_by(10ms);
  }

  hal::SimClock clock{1s};
  BusPair buses;
  sim::SimScoutMini base;
  scout_mini::ScoutMini driver;
};

BusPair virtual_pair(hal::Clock& clock, const std::string& name) {
  return {std::make_unique<hal::VirtualCanBus>(name, clock),
          std::make_unique<hal::VirtualCanBus>(name, clock)};
}

// The host end is a real SlcanBus opened on the pty's slave path; the base end is an SlcanBus
// on the pty master (an slcan adapter is symmetric: frames out as t-lines, t-lines in as frames).
BusPair slcan_pair(hal::Clock& clock) {
  int master = -1;
  int slave = -1;
  char name[256];
  if (openpty(&master, &slave, name, nullptr, nullptr) != 0) return {};
  auto host = hal::SlcanBus::open(name, 115200, 500, clock);
  close(slave);  // the host bus has its own descriptor now
  EXPECT_TRUE(host.bus) << host.error;
  auto adapter = std::make_unique<hal::SlcanBus>(hal::adopt_serial_fd(master), "pty-master", clock);
  return {std::move(host.bus), std::move(adapter)};
}

void enables_drives_and_stops(Rig& rig) {
  // Power-on: standby; the driver requests CAN mode until the base confirms it.
  EXPECT_EQ(rig.base.mode(), ControlMode::kStandby);
  rig.run(300ms);
  EXPECT_EQ(rig.base.mode(), ControlMode::kCan);
  EXPECT_TRUE(rig.driver.state().in_can_mode());
  EXPECT_GE(rig.driver.counters().mode_requests, 1U);

  // Drive forward-left while turning; the base accelerates within its limit (1.5 m/s^2).
  rig.run(1s, Command{0.6, 0.3, 0.4});
  EXPECT_NEAR(rig.base.velocity().vx_mps, 0.6, 1e-9);
  EXPECT_NEAR(rig.base.velocity().vy_mps, 0.3, 1e-9);
  EXPECT_NEAR(rig.base.velocity().wz_radps, 0.4, 1e-9);
  EXPECT_NEAR(rig.driver.state().velocity.vx_mps, 0.6, 1e-3) << "measured via 0x221";
  // Odometry from 0x221 follows the base's true pose.
  EXPECT_NEAR(rig.driver.state().odom.x_m, rig.base.pose().x_m, 0.03);
  EXPECT_NEAR(rig.driver.state().odom.y_m, rig.base.pose().y_m, 0.03);
  EXPECT_NEAR(rig.driver.state().odom.theta_rad, rig.base.pose().theta_rad, 0.02);
  EXPECT_GT(rig.driver.id_stats(0x221).rate_hz(), 45.0);
  EXPECT_LT(rig.driver.id_stats(0x221).rate_hz(), 55.0);
  EXPECT_GT(rig.driver.id_stats(0x211).rate_hz(), 9.0);

  // Told to stop: the very next command period carries zero and the base decelerates at once.
  const double before = rig.base.velocity().vx_mps;
  rig.tick(Command{0, 0, 0});
  rig.tick(Command{0, 0, 0});
  EXPECT_LT(rig.base.velocity().vx_mps, before) << "decelerating within one control period";
  rig.run(600ms, Command{0, 0, 0});
  EXPECT_EQ(rig.base.velocity().vx_mps, 0.0);
}

}  // namespace

// Every scenario runs over the in-process virtual bus and over slcan on a pseudo-terminal.
class ScoutDriverSim : public ::testing::TestWithParam<std::string> {
 protected:
  std::unique_ptr<Rig> make_rig() {
    auto rig = std::make_unique<Rig>([&](hal::Clock& c) {
      return GetParam() == "slcan" ? slcan_pair(c) : virtual_pair(c, "rig");
    });
    EXPECT_TRUE(rig->buses.first && rig->buses.second);
    return rig;
  }
  bool is_virtual() const { return GetParam() == "virtual"; }
};

INSTANTIATE_TEST_SUITE_P(Transports, ScoutDriverSim, ::testing::Values("virtual", "slcan"),
                         [](const auto& p) { return p.param; });

TEST_P(ScoutDriverSim, EnablesDrivesAndStops) {
  auto rig_ptr = make_rig();
  enables_drives_and_stops(*rig_ptr);
}

TEST_P(ScoutDriverSim, BaseStopsByItselfWhenTheDriverGoesSilent) {
  auto rig_ptr = make_rig();
  Rig& rig = *rig_ptr;
  rig.run(1s, Command{0.5, 0, 0});
  ASSERT_NEAR(rig.base.velocity().vx_mps, 0.5, 1e-9);
  rig.run(490ms, Command{0, 0, 0, false});
  EXPECT_NEAR(rig.base.velocity().vx_mps, 0.5, 1e-9) << "within the 500 ms timeout it keeps going";
  rig.run(500ms, Command{0, 0, 0, false});
  EXPECT_EQ(rig.base.velocity().vx_mps, 0.0);
  EXPECT_TRUE(rig.driver.state().fault_word & scout_mini::fault::kHostCommLost);
}

TEST_P(ScoutDriverSim, RecoversAfterABasePowerCycle) {
  auto rig_ptr = make_rig();
  Rig& rig = *rig_ptr;
  rig.run(500ms, Command{0.3, 0, 0});
  ASSERT_EQ(rig.base.mode(), ControlMode::kCan);
  rig.base.power_cycle();
  rig.run(300ms, Command{0.3, 0, 0});
  EXPECT_EQ(rig.base.mode(), ControlMode::kCan) << "0x421 re-sent after the fallback";
  EXPECT_GE(rig.driver.counters().mode_fallbacks, 1U);
  rig.run(500ms, Command{0.3, 0, 0});
  EXPECT_NEAR(rig.base.velocity().vx_mps, 0.3, 1e-9);
}

TEST_P(ScoutDriverSim, NeverFightsTheRemoteControl) {
  auto rig_ptr = make_rig();
  Rig& rig = *rig_ptr;
  rig.run(500ms, Command{0.3, 0, 0});
  rig.base.set_rc_takeover(true);
  rig.run(200ms, Command{0.3, 0, 0});
  const auto requests = rig.driver.counters().mode_requests;
  const auto sent = rig.driver.counters().commands_sent;
  rig.run(1s, Command{0.3, 0, 0});
  EXPECT_TRUE(rig.driver.state().rc_has_control());
  EXPECT_EQ(rig.driver.counters().mode_requests, requests) << "no 0x421 while the RC holds it";
  EXPECT_EQ(rig.driver.counters().commands_sent, sent) << "no 0x111 either";
  EXPECT_GT(rig.driver.counters().commands_withheld_rc, 90U);
  rig.base.set_rc_takeover(false);
  rig.run(300ms, Command{0.3, 0, 0});
  EXPECT_EQ(rig.base.mode(), ControlMode::kCan) << "taken back after the RC let go";
}

TEST_P(ScoutDriverSim, ReportsEachFault) {
  auto rig_ptr = make_rig();
  Rig& rig = *rig_ptr;
  rig.run(500ms);
  rig.base.set_estop(true);
  rig.run(200ms);
  EXPECT_TRUE(rig.driver.state().estop());
  rig.base.set_estop(false);
  rig.run(300ms);
  EXPECT_FALSE(rig.driver.state().estop());
  EXPECT_TRUE(rig.driver.state().in_can_mode()) << "re-enabled after the E-stop release";

  rig.base.set_under_voltage(true);
  rig.run(200ms);
  EXPECT_TRUE(rig.driver.state().stopping_faults() & scout_mini::fault::kBatteryUnderVoltageFault);
  rig.base.set_under_voltage(false);
  rig.run(200ms);
  EXPECT_EQ(rig.driver.state().stopping_faults(), 0);

  // A motor protection fault latches until 0x441.
  rig.base.inject_motor_fault(2);
  rig.run(300ms, Command{0.4, 0, 0});
  EXPECT_TRUE(rig.driver.state().stopping_faults() & scout_mini::fault::kMotorDriverError);
  EXPECT_EQ(rig.driver.state().motors[1].driver_state & 0x04, 0x04) << "motor 2 over-current";
  EXPECT_EQ(rig.base.velocity().vx_mps, 0.0) << "a faulted base does not move";
  rig.run(500ms, Command{0.4, 0, 0});
  EXPECT_TRUE(rig.driver.state().stopping_faults()) << "latched";
  rig.driver.clear_faults();
  rig.run(300ms, Command{0.4, 0, 0});
  EXPECT_EQ(rig.driver.state().stopping_faults(), 0);
  EXPECT_GT(rig.base.velocity().vx_mps, 0.0);
}

TEST_P(ScoutDriverSim, DetectsFeedbackSilenceAndBusOff) {
  auto rig_ptr = make_rig();
  Rig& rig = *rig_ptr;
  rig.run(300ms);
  EXPECT_FALSE(rig.driver.feedback_silent(rig.clock.now()));
  rig.base.set_feedback_silent(true);
  rig.run(250ms);
  EXPECT_TRUE(rig.driver.feedback_silent(rig.clock.now()));
  rig.base.set_feedback_silent(false);
  rig.run(100ms);
  EXPECT_FALSE(rig.driver.feedback_silent(rig.clock.now()));

  if (!is_virtual()) return;  // bus-off injection needs the virtual controller
  auto& host = static_cast<hal::VirtualCanBus&>(*rig.buses.first);
  host.inject_bus_off(true);
  rig.run(50ms);
  EXPECT_TRUE(rig.driver.bus_off());
  EXPECT_GE(rig.driver.counters().write_errors, 4U);
  EXPECT_GE(rig.driver.counters().error_frames, 1U);
  host.inject_bus_off(false);
  rig.run(50ms);
  EXPECT_FALSE(rig.driver.bus_off());
}

TEST_P(ScoutDriverSim, ReadsTheVersion) {
  auto rig_ptr = make_rig();
  Rig& rig = *rig_ptr;
  rig.run(100ms);
  rig.driver.request_version();
  rig.run(50ms);
  ASSERT_TRUE(rig.driver.state().version.has_value());
  EXPECT_EQ(rig.driver.state().version->control_sw, 0x0205);
}

TEST(ScoutDriverSim, ProtocolV1IsReportedNotDriven) {
  hal::SimClock clock;
  hal::VirtualCanBus host("rig8", clock);
  hal::VirtualCanBus v1base("rig8", clock);
  scout_mini::ScoutMini driver(host, {});
  (void)v1base.send(hal::CanFrame::standard(0x151, {0, 0, 0, 0, 0, 0, 0, 0}));
  driver.poll(clock.now());
  EXPECT_TRUE(driver.state().protocol_v1);
  clock.advance_by(1s);
  driver.poll(clock.now());
  EXPECT_EQ(driver.counters().mode_requests, 0U) << "a V1 base is not talked to in V2";
}

// The simulated base's realism knobs: command latency and velocity-feedback noise.
TEST(SimScoutMini, CommandsTakeEffectAfterTheLatencyAndFeedbackIsNoisyOnlyWhileMoving) {
  hal::SimClock clock{1s};
  hal::VirtualCanBus host("latency", clock);
  hal::VirtualCanBus base_end("latency", clock);
  sim::SimScoutConfig cfg;
  cfg.command_latency = 40ms;
  cfg.feedback_noise_rel = 0.05;
  sim::SimScoutMini base(base_end, cfg);
  std::vector<double> reported;
  auto step = [&](hal::Nanos d, bool drive) {
    const hal::Nanos end = clock.now() + d;
    while (clock.now() < end) {
      base.step(clock.now());
      while (auto f = host.receive()) {
        const auto m = scout_mini::decode(f->frame);
        if (!m.message) continue;
        if (const auto* v = std::get_if<scout_mini::MotionState>(&*m.message)) {
          reported.push_back(v->vx_mps);
        }
      }
      if (drive) {
        (void)host.send(scout_mini::encode_motion(0.6, 0, 0, {}).frame);
      }
      clock.advance_by(5ms);
    }
  };
  (void)host.send(scout_mini::encode_control_mode(ControlMode::kCan));
  step(50ms, false);
  ASSERT_EQ(base.mode(), ControlMode::kCan);
  // First command at t0; nothing moves for 40 ms, then the base accelerates.
  step(35ms, true);
  EXPECT_EQ(base.velocity().vx_mps, 0.0) << "still within the command latency";
  step(20ms, true);
  EXPECT_GT(base.velocity().vx_mps, 0.0) << "the first command took effect";
  step(1s, true);
  EXPECT_NEAR(base.velocity().vx_mps, 0.6, 1e-9) << "the true velocity is exact";
  reported.clear();
  step(1s, true);
  ASSERT_GE(reported.size(), 45U);
  double mean = 0;
  int differing = 0;
  for (double v : reported) {
    mean += v / static_cast<double>(reported.size());
    if (std::abs(v - 0.6) >= 0.001) ++differing;
  }
  EXPECT_NEAR(mean, 0.6, 0.02);
  EXPECT_GT(differing, 30) << "the reported velocity carries noise";
  step(1s, false);  // no commands for 500 ms: the base stops by itself
  reported.clear();
  step(200ms, false);
  ASSERT_FALSE(reported.empty());
  for (double v : reported)
    EXPECT_EQ(v, 0.0) << "standing: the encoders read zero";
}
