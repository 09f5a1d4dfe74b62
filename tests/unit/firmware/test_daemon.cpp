// companiond's task table and daemon on the simulated clock, with a real NOTIFY_SOCKET.
#include <gtest/gtest.h>
#include <spdlog/sinks/ringbuffer_sink.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <thread>
#include <utility>
#include <vector>

#include "firmware/config/config_loader.hpp"
#include "firmware/daemon.hpp"
#include "firmware/task_table.hpp"
#include "hal/can/virtual_can.hpp"
#include "hal/sim_clock.hpp"
#include "sim/sim_amfitrack.hpp"
#include "sim/sim_scout_mini.hpp"
#include "support/notify_socket.hpp"

using namespace std::chrono_literals;
using core::Nanos;

namespace {

struct SimDaemon {
  explicit SimDaemon(const firmware::DaemonConfig& cfg)
      : daemon(cfg, notifier), executor(clock, firmware::group_table(), daemon.bindings()) {
    daemon.attach(executor);
    daemon.mark_initialized();
  }
  // Single-threaded deterministic run until `end`; `during` runs on the task thread each 10 ms
  // (a test hook scheduled like a task, after the table's tasks).
  void run_until(Nanos end) {
    clock.set_horizon(end);
    std::thread stopper([&] {
      clock.wait_until_idle_at(end);
      executor.stop();
    });
    executor.run(0s);
    stopper.join();
  }
  hal::SimClock clock;
  hal::SystemdNotifier notifier;
  firmware::Daemon daemon;
  firmware::Executor executor;
};

firmware::DaemonConfig defaults() {
  return *firmware::load_default_config().config;
}

}  // namespace

TEST(TaskTable, HasTheRowsOfTheDesign) {
  const auto& t = firmware::task_table();
  auto rate = [&](std::string_view name) {
    for (const auto& row : t) {
      if (row.spec.name == name) return row.spec.rate_hz;
    }
    return 0U;
  };
  EXPECT_EQ(rate("tracker"), 120U);
  EXPECT_EQ(rate("base"), 50U);
  EXPECT_EQ(rate("lidar"), 10U);
  EXPECT_EQ(rate("policy"), 30U);
  EXPECT_EQ(rate("control"), 100U);
  EXPECT_EQ(rate("supervisor"), 100U);
  for (const auto& row : t) {
    EXPECT_LT(row.spec.group, firmware::group_table().size());
    EXPECT_LT(firmware::group_table()[row.spec.group].fifo_priority, 50);
  }
  // The 10 Hz lidar task never shares a thread with the 100 Hz control task.
  uint8_t lidar_group = 0;
  uint8_t control_group = 0;
  for (const auto& row : t) {
    if (row.spec.name == "lidar") lidar_group = row.spec.group;
    if (row.spec.name == "control") control_group = row.spec.group;
  }
  EXPECT_NE(lidar_group, control_group);
}

TEST(Daemon, WithNoDevicesItHoldsBecauseTheTrackerIsSilentAndSaysSo) {
  test_support::NotifySocket sock;
  ASSERT_TRUE(sock.ok());
  sock.export_env();
  SimDaemon d(defaults());
  d.run_until(3s);
  unsetenv("NOTIFY_SOCKET");

  const auto safety = d.daemon.safety().read();
  ASSERT_TRUE(safety.has_value());
  EXPECT_EQ(safety->value.state, core::SafetyState::kHold);
  EXPECT_EQ(safety->value.reason, core::Reason::kTrackerSilent);
  EXPECT_FALSE(safety->value.motion_allowed);
  const auto cmd = d.daemon.command().read();
  ASSERT_TRUE(cmd.has_value());
  EXPECT_TRUE(cmd->value.is_zero());
  EXPECT_EQ(cmd->count, 301U) << "the control task streamed a command every 10 ms";

  const std::string status = d.daemon.status_line();
  EXPECT_EQ(status.rfind("HOLD: tracker silent", 0), 0U) << status;
  EXPECT_NE(status.find("control 100Hz"), std::string::npos) << status;
  EXPECT_EQ(status.find("not yet implemented"), std::string::npos) << "every task is real";
  const auto sent = sock.receive_containing("STATUS=HOLD: tracker silent", 1s);
  EXPECT_TRUE(sent.has_value());
}

namespace {
// Collects every notification while `body` runs (systemd reads promptly; so must the test, or
// the sender blocks once the socket's small queue is full).
template <typename F>
std::vector<std::string> collect_notifications(F body) {
  test_support::NotifySocket sock;
  EXPECT_TRUE(sock.ok());
  sock.export_env();
  std::atomic<bool> done{false};
  std::vector<std::string> msgs;
  std::thread drain([&] {
    while (!done.load()) {
      if (auto m = sock.receive(20ms)) msgs.push_back(*m);
    }
    while (auto m = sock.receive(0ms))
      msgs.push_back(*m);
  });
  body();
  done = true;
  drain.join();
  unsetenv("NOTIFY_SOCKET");
  return msgs;
}

int count(const std::vector<std::string>& msgs, const std::string& m) {
  return static_cast<int>(std::count(msgs.begin(), msgs.end(), m));
}
}  // namespace

TEST(Daemon, PingsTheWatchdogWhileControlRuns) {
  setenv("WATCHDOG_USEC", "400000", 1);
  setenv("WATCHDOG_PID", std::to_string(getpid()).c_str(), 1);
  const auto msgs = collect_notifications([] {
    SimDaemon d(defaults());
    d.run_until(1s);
  });
  unsetenv("WATCHDOG_USEC");
  unsetenv("WATCHDOG_PID");
  // Every 100 ms (a quarter of WatchdogSec) over one second, while holding (control runs).
  const int pings = count(msgs, "WATCHDOG=1");
  EXPECT_GE(pings, 9);
  EXPECT_LE(pings, 11);
}

namespace {

// Replaces the control task's function by wrap(its function) and gives it its own thread (the
// planning group's), so the supervisor's realtime group runs on whatever the wrapper does.
// Returns the control task's index.
template <typename Wrap>
size_t wrap_control_task(std::vector<firmware::TaskBinding>& tasks, Wrap wrap) {
  size_t control = tasks.size();
  for (size_t i = 0; i < tasks.size(); ++i) {
    if (tasks[i].spec.name != "control") continue;
    control = i;
    tasks[i].fn = wrap(tasks[i].fn);
    tasks[i].spec.group = firmware::kGroupPlanning;
  }
  return control;
}

}  // namespace

TEST(Daemon, StopsPingingTheWatchdogWhenControlStalls) {
  setenv("WATCHDOG_USEC", "400000", 1);
  setenv("WATCHDOG_PID", std::to_string(getpid()).c_str(), 1);
  std::vector<std::string> before;
  std::vector<std::string> after;
  auto cfg = defaults();
  {
    // The control task hangs from 1 s on (its thread "works" forever in virtual time): the
    // supervisor must fault and the pings must stop, while other groups keep running.
    hal::SimClock clock;
    hal::SystemdNotifier notifier;
    firmware::Daemon daemon(cfg, notifier);
    auto tasks = daemon.bindings();
    wrap_control_task(tasks, [&clock](const firmware::TaskFn& real) {
      return [&clock, real](const core::Tick& tick) {
        if (tick.now >= 1s) clock.sleep_until(tick.now + 1h);
        real(tick);
      };
    });
    firmware::Executor ex(clock, firmware::group_table(), tasks);
    daemon.attach(ex);
    daemon.mark_initialized();
    before = collect_notifications([&] {
      clock.set_horizon(1s);
      ex.start(0s, false);
      clock.wait_until_idle_at(1s);
    });
    after = collect_notifications([&] {
      clock.set_horizon(3s);
      clock.wait_until_idle_at(3s);
      ex.stop();
    });
    EXPECT_EQ(daemon.safety().read()->value.state, core::SafetyState::kFault);
    EXPECT_EQ(daemon.safety().read()->value.reason, core::Reason::kControlStalled);
  }
  unsetenv("WATCHDOG_USEC");
  unsetenv("WATCHDOG_PID");
  std::string all;
  for (const auto& m : before)
    all += m + " / ";
  EXPECT_GE(count(before, "WATCHDOG=1"), 9) << all;
  EXPECT_LE(count(after, "WATCHDOG=1"), 2) << "at most the pings before the stall was seen";
}

namespace {

// The control task runs late (15 ms of virtual work, past its 10 ms deadline) at the given
// times; returns whether 'control overrun' was among the supervisor's reasons at 1.5 s, and the
// scheduler's overrun count. Through the executor's statistics and the daemon's supervisor task,
// as on the robot.
std::pair<bool, uint64_t> overrun_reason_after(const std::vector<core::Nanos>& late_at) {
  auto cfg = defaults();
  hal::SimClock clock;
  hal::SystemdNotifier notifier;
  firmware::Daemon daemon(cfg, notifier);
  auto tasks = daemon.bindings();
  const size_t control = wrap_control_task(tasks, [&clock, &late_at](const firmware::TaskFn& real) {
    return [&clock, real, late_at](const core::Tick& tick) {
      real(tick);
      for (const core::Nanos at : late_at) {
        if (tick.now == at) clock.sleep_until(tick.now + 15ms);
      }
    };
  });
  firmware::Executor ex(clock, firmware::group_table(), tasks);
  daemon.attach(ex);
  daemon.mark_initialized();
  clock.set_horizon(1500ms);
  ex.start(0s, false);
  clock.wait_until_idle_at(1500ms);
  const uint32_t mask = daemon.safety().read()->value.active_mask;
  ex.stop();
  const bool overrun = (mask >> core::reason_index(core::Reason::kControlOverrun)) & 1U;
  return {overrun, ex.stats(control).overruns()};
}

}  // namespace

TEST(Daemon, OneLateControlRunIsCountedButThreeWithinASecondAreAHoldReason) {
  const auto [one_reason, one_count] = overrun_reason_after({1000ms});
  EXPECT_EQ(one_count, 1U);
  EXPECT_FALSE(one_reason) << "a single late step is counted, not a hold (3 within 1 s)";
  const auto [three_reason, three_count] = overrun_reason_after({1000ms, 1200ms, 1400ms});
  EXPECT_EQ(three_count, 3U);
  EXPECT_TRUE(three_reason);
  const auto [spread_reason, spread_count] = overrun_reason_after({100ms, 700ms, 1400ms});
  EXPECT_EQ(spread_count, 3U);
  EXPECT_FALSE(spread_reason) << "three overruns spread over 1.3 s";
}

TEST(Daemon, ShutdownStopsTheRobotBeforeReportingComplete) {
  SimDaemon d(defaults());
  bool complete_seen = false;
  d.clock.set_horizon(1s);
  std::thread stopper([&] {
    d.clock.wait_until_idle_at(1s);
    EXPECT_FALSE(d.daemon.shutdown_complete());
    d.daemon.request_shutdown();
    d.clock.set_horizon(1s + 50ms);
    d.clock.wait_until_idle_at(1s + 50ms);
    complete_seen = d.daemon.shutdown_complete();
    d.executor.stop();
  });
  d.executor.run(0s);
  stopper.join();
  EXPECT_TRUE(complete_seen);
  EXPECT_EQ(d.daemon.safety().read()->value.reason, core::Reason::kShutdown);
}

TEST(Daemon, SameInputsSameOutputsBitForBit) {
  auto run = [] {
    SimDaemon d(defaults());
    d.run_until(2500ms);
    const auto s = d.daemon.safety().read();
    const auto c = d.daemon.command().read();
    return std::make_tuple(s->count, s->stamp, static_cast<int>(s->value.reason), c->count,
                           c->stamp, d.daemon.status_line());
  };
  EXPECT_EQ(run(), run());
}

// The daemon with the simulated Scout Mini on a virtual CAN bus: the base task enables CAN mode
// and reports the base's health to the supervisor; the control task streams the gated command.
namespace {
struct DaemonWithBase {
  // `script` runs in the world task at every 5 ms step, before the daemon's tasks.
  // With `with_tracker`, a simulated Amfitrack streams the person's sensor too.
  explicit DaemonWithBase(std::function<void(Nanos, DaemonWithBase&)> script = {},
                          bool with_tracker = false,
                          const firmware::DaemonConfig& config = defaults())
      : daemon(config, notifier), base_bus("daemon-base", clock), base(base_bus) {
    auto host = std::make_unique<hal::VirtualCanBus>("daemon-base", clock);
    host_bus = host.get();
    EXPECT_TRUE(daemon.attach_base(std::move(host)));
    if (with_tracker) daemon.attach_tracker(tracker.host_link());
    auto tasks = daemon.bindings();
    tasks.push_back(
        {core::TaskSpec{"world", 200, 100, 0, 255}, [this, script](const core::Tick& t) {
           if (script) script(t.now, *this);
           base.step(t.now);
           tracker.step(t.now);
         }});
    executor = std::make_unique<firmware::Executor>(clock, firmware::group_table(), tasks);
    daemon.attach(*executor);
    daemon.mark_initialized();
  }
  void run_until(Nanos end) {
    clock.set_horizon(end);
    std::thread stopper([&] {
      clock.wait_until_idle_at(end);
      executor->stop();
    });
    executor->run(0s);
    stopper.join();
  }
  hal::SimClock clock;
  hal::SystemdNotifier notifier;
  firmware::Daemon daemon;
  hal::VirtualCanBus base_bus;
  hal::VirtualCanBus* host_bus = nullptr;  // the daemon's end (owned by the daemon)
  sim::SimScoutMini base;
  sim::SimAmfitrack tracker;
  std::unique_ptr<firmware::Executor> executor;
};

bool active(const firmware::SafetySnapshot& s, core::Reason r) {
  return (s.active_mask >> core::reason_index(r) & 1U) != 0;
}
}  // namespace

TEST(DaemonWithBase, EnablesTheBaseStreamsZeroWhileHoldingAndSeesItsFeedback) {
  DaemonWithBase d;
  d.run_until(2s);
  EXPECT_EQ(d.base.mode(), scout_mini::ControlMode::kCan) << "the base task enabled CAN mode";
  EXPECT_GE(d.base.commands_accepted(), 150U) << "0x111 streamed at the control rate";
  EXPECT_EQ(d.base.velocity().vx_mps, 0.0) << "holding (tracker silent): zero commanded";
  const auto s = d.daemon.safety().read()->value;
  EXPECT_EQ(s.state, core::SafetyState::kHold);
  EXPECT_EQ(s.reason, core::Reason::kTrackerSilent);
  EXPECT_FALSE(active(s, core::Reason::kBaseFeedbackSilent)) << "the base's feedback arrives";
  const auto h = d.daemon.base_health().read();
  ASSERT_TRUE(h);
  EXPECT_TRUE(h->value.can_mode);
}

TEST(DaemonWithBase, BaseSilenceAndEstopReachTheSupervisor) {
  bool silent_seen = false;
  DaemonWithBase d([&](Nanos now, DaemonWithBase& w) {
    if (now == 1s) w.base.set_feedback_silent(true);
    if (now == 1500ms) {
      silent_seen = active(w.daemon.safety().read()->value, core::Reason::kBaseFeedbackSilent);
      w.base.set_feedback_silent(false);
      w.base.set_estop(true);
    }
  });
  d.run_until(2s);
  EXPECT_TRUE(silent_seen);
  const auto s = d.daemon.safety().read()->value;
  EXPECT_EQ(s.state, core::SafetyState::kFault);
  EXPECT_EQ(s.reason, core::Reason::kBaseEstop);
}

TEST(DaemonWithBase, ShutdownCompletesOnlyOnceTheBaseReportsStandstill) {
  bool complete_before_feedback = true;
  DaemonWithBase d([&](Nanos now, DaemonWithBase& w) {
    if (now == 1s) {
      w.base.set_feedback_silent(true);  // no confirmation possible
      w.daemon.request_shutdown();
    }
    if (now == 1400ms) {
      complete_before_feedback = w.daemon.shutdown_complete();
      w.base.set_feedback_silent(false);
    }
  });
  d.run_until(1600ms);
  EXPECT_FALSE(complete_before_feedback) << "zero commanded is not enough without the base's word";
  EXPECT_TRUE(d.daemon.shutdown_complete());
}

TEST(DaemonWithBase, FailedSendsAreWarnedAtMostOncePerInterval) {
  // Capture the log lines (the default logger outside the daemon is synchronous).
  auto ring = std::make_shared<spdlog::sinks::ringbuffer_sink_mt>(10000);
  auto previous = spdlog::default_logger();
  spdlog::set_default_logger(std::make_shared<spdlog::logger>("capture", ring));
  DaemonWithBase d([](Nanos now, DaemonWithBase& w) {
    if (now == 1s) w.host_bus->inject_bus_off(true);  // 0x111 fails at 100 Hz from here on
  });
  d.run_until(3500ms);
  spdlog::set_default_logger(previous);
  int warnings = 0;
  bool counted = false;
  for (const auto& line : ring->last_formatted()) {
    if (line.find("base: motion command not sent: bus-off") == std::string::npos) continue;
    ++warnings;
    counted = counted || line.find("similar suppressed") != std::string::npos;
  }
  // 250 failed sends in 2.5 s, warning_interval_ms = 1000: three lines, not 250.
  EXPECT_EQ(warnings, 3);
  EXPECT_TRUE(counted) << "later lines say how many were held back";
  EXPECT_TRUE(active(d.daemon.safety().read()->value, core::Reason::kCanBusOff));
}

// The tracker in the daemon: frames -> gate -> supervisor, and the person's state in odom.
namespace {
// The default config mounts the source turned by pi (its X to the robot's back), 0.35 m up:
// a sensor at (-1.2, 0.3) in the source frame is 1.2 m ahead and 0.3 m to the right.
void person_ahead(sim::SimAmfitrack& t) {
  t.set_sensor_pose(-1.2, 0.3, 0.0, std::numbers::pi);
}

bool tracker_ok(const firmware::SafetySnapshot& s) {
  return !active(s, core::Reason::kTrackerSilent) &&
         !active(s, core::Reason::kTrackerConfidenceLow) && !active(s, core::Reason::kPersonLost);
}
}  // namespace

TEST(DaemonWithTracker, ConfidenceDropHoldsWithinAFrameAndRecoversAfterTheHysteresis) {
  auto ring = std::make_shared<spdlog::sinks::ringbuffer_sink_mt>(10000);
  auto previous = spdlog::default_logger();
  spdlog::set_default_logger(std::make_shared<spdlog::logger>("capture", ring));
  std::map<Nanos, firmware::SafetySnapshot> seen;
  DaemonWithBase d(
      [&](Nanos now, DaemonWithBase& w) {
        if (now == 0ms) person_ahead(w.tracker);
        if (now == 3s) w.tracker.set_quality(60);  // metal near the sensor: quality collapses
        if (now == 4s) w.tracker.set_quality(230);
        for (Nanos at : {2900ms, 3020ms, 4500ms, 5000ms, 5400ms}) {
          if (now == at) seen[at] = w.daemon.safety().read()->value;
        }
      },
      true);
  d.run_until(5500ms);
  spdlog::set_default_logger(previous);

  EXPECT_TRUE(tracker_ok(seen[2900ms])) << "good frames at 120 Hz: nothing to say";
  EXPECT_TRUE(active(seen[3020ms], core::Reason::kTrackerConfidenceLow))
      << "BAD within a frame, judged by the next supervisor run";
  EXPECT_TRUE(active(seen[4500ms], core::Reason::kTrackerConfidenceLow))
      << "GOOD again at 4.1 s, but the supervisor waits tracker_confidence_recover_ms";
  EXPECT_TRUE(active(seen[5000ms], core::Reason::kTrackerConfidenceLow));
  EXPECT_TRUE(tracker_ok(seen[5400ms]));

  bool logged = false;
  for (const auto& line : ring->last_formatted()) {
    logged = logged ||
             (line.find("tracker confidence BAD (quality low), quality 60") != std::string::npos);
  }
  EXPECT_TRUE(logged) << "the transition names the gate's reason and the value";

  const std::string status = d.daemon.status_line();
  EXPECT_NE(status.find("| tracker GOOD q230 120Hz"), std::string::npos) << status;
  EXPECT_NE(status.find("person 1.24m"), std::string::npos) << status;
  const auto h = d.daemon.tracker_health().read();
  ASSERT_TRUE(h);
  EXPECT_NEAR(h->value.rate_hz, 120.0, 2.0);
  EXPECT_EQ(h->value.dropped_frames, 0U);
  EXPECT_TRUE(h->value.link_up);
}

TEST(DaemonWithTracker, EstimatesThePersonInOdom) {
  DaemonWithBase d(
      [](Nanos now, DaemonWithBase& w) {
        if (now == 0ms) person_ahead(w.tracker);
      },
      true);
  d.run_until(2s);
  const auto t = d.daemon.human_track().read();
  ASSERT_TRUE(t);
  ASSERT_TRUE(t->value.valid);
  // The base stands at the odom origin: odom = base_link here.
  const auto h = core::human_state(t->value, 2s, core::Pose2{}, d.daemon.human_config());
  EXPECT_NEAR(h.pose_odom.x_m, 1.2, 1e-3);
  EXPECT_NEAR(h.pose_odom.y_m, -0.3, 1e-3);
  EXPECT_NEAR(h.pose_odom.theta_rad, 0.0, 1e-3) << "sensor facing the source's -X: forward";
  EXPECT_NEAR(std::hypot(h.velocity_odom.x_m, h.velocity_odom.y_m), 0.0, 1e-3);
  EXPECT_LT(h.age, 20ms);
  const auto th = d.daemon.tracker_health().read()->value;
  EXPECT_NEAR(th.person_distance_m, std::hypot(1.2, 0.3), 1e-3);
  EXPECT_EQ(th.filter_rejected, 0U);
}

TEST(DaemonWithTracker, SilenceAndDistanceReachTheSupervisor) {
  std::map<Nanos, firmware::SafetySnapshot> seen;
  DaemonWithBase d(
      [&](Nanos now, DaemonWithBase& w) {
        if (now == 0ms) person_ahead(w.tracker);
        if (now == 2s) w.tracker.set_silent(true);
        if (now == 2500ms) {
          w.tracker.set_silent(false);
          w.tracker.set_sensor_pose(-5.5, 0.0, 0.0, std::numbers::pi);  // 5.5 m away
        }
        for (Nanos at : {1900ms, 2200ms, 2700ms}) {
          if (now == at) seen[at] = w.daemon.safety().read()->value;
        }
      },
      true);
  d.run_until(2800ms);
  EXPECT_TRUE(tracker_ok(seen[1900ms]));
  EXPECT_TRUE(active(seen[2200ms], core::Reason::kTrackerSilent));
  EXPECT_TRUE(active(seen[2700ms], core::Reason::kPersonLost));
}

// The lidar in the daemon: VLP-16 packets over a real UDP socket (loopback) -> scans -> voxel
// grid -> costmap snapshot; the supervisor sees the lidar and the costmap fresh.
#include "hal/net/udp_socket.hpp"
#include "vlp16/vlp16_codec.hpp"

namespace {
// A VLP-16 at 600 rpm in a round room of radius 3 m: every beam hits the wall.
class RoundRoom {
 public:
  explicit RoundRoom(uint16_t port) : port_(port) {
    std::string err;
    tx_ = hal::UdpSender::open(err);
  }
  // Sends every packet due up to `now`.
  void step(Nanos now) {
    const double period_us = 1327.104;
    while (next_us_ <= core::to_us(now)) {
      vlp16::RawDataPacket p;
      p.timestamp_us = static_cast<uint32_t>(std::fmod(next_us_, 3.6e9));
      for (size_t b = 0; b < vlp16::kBlocks; ++b) {
        const double t = next_us_ + vlp16::kBlockUs * static_cast<double>(b);
        p.blocks[b].azimuth = static_cast<uint16_t>(std::fmod(t * 0.36, 36000.0));
        for (size_t k = 0; k < vlp16::kChannels; ++k) {
          const size_t laser = k % 16;
          const double el = vlp16::laser_table(vlp16::Product::kVlp16).elevation_rad[laser];
          p.blocks[b].distance[k] = static_cast<uint16_t>(3.0 / std::cos(el) / 0.002);
          p.blocks[b].intensity[k] = 50;
        }
      }
      const auto bytes = vlp16::encode_data_packet(p);
      tx_->send_to({"127.0.0.1", port_}, bytes);
      next_us_ += period_us;
    }
  }

 private:
  uint16_t port_;
  std::unique_ptr<hal::UdpSender> tx_;
  double next_us_ = 0;
};
}  // namespace

TEST(DaemonWithLidar, BuildsTheCostmapAndFeedsTheSupervisor) {
  // Stamped at the drain: the test runs on the simulated clock.
  auto opened = hal::UdpReceiver::open({"127.0.0.1", 0}, 4 << 20, hal::UdpStamp::kDrain);
  ASSERT_TRUE(opened.receiver) << opened.error;
  RoundRoom room(opened.receiver->port());
  std::map<Nanos, firmware::SafetySnapshot> seen;
  std::unique_ptr<DaemonWithBase> d;
  d = std::make_unique<DaemonWithBase>([&](Nanos now, DaemonWithBase& w) {
    room.step(now);
    if (now == 50ms || now == 1500ms) seen[now] = w.daemon.safety().read()->value;
  });
  d->daemon.attach_lidar(std::move(opened.receiver));
  d->run_until(1600ms);
  EXPECT_TRUE(active(seen[50ms], core::Reason::kLidarSilent) ||
              active(seen[50ms], core::Reason::kCostmapStale))
      << "no scan yet";
  EXPECT_FALSE(active(seen[1500ms], core::Reason::kLidarSilent));
  EXPECT_FALSE(active(seen[1500ms], core::Reason::kCostmapStale));
  const auto health = d->daemon.lidar_health().read();
  ASSERT_TRUE(health);
  EXPECT_GE(health->value.scans, 12U) << "10 Hz";
  EXPECT_EQ(health->value.decode_errors, 0U);
  EXPECT_EQ(health->value.lost_packets, 0U);
  const auto map = d->daemon.costmap().latest();
  ASSERT_TRUE(map);
  // The wall (3 m from the sensor, which is 0.10 m ahead of base_link) is lethal; the middle of
  // the room is free; the robot's own cell is free.
  EXPECT_EQ(map->at(3.1, 0.0), core::kCostLethal);
  EXPECT_EQ(map->at(0.1, -3.0), core::kCostLethal);
  EXPECT_EQ(map->at(1.0, 0.5), 0);
  EXPECT_EQ(map->at(0.0, 0.0), 0);
  EXPECT_NE(d->daemon.status_line().find("| lidar "), std::string::npos) << d->daemon.status_line();
}

TEST(DaemonWithTrackerAndLidar, ChoosesACompanionPointAroundThePerson) {
  // Stamped at the drain: the test runs on the simulated clock.
  auto opened = hal::UdpReceiver::open({"127.0.0.1", 0}, 4 << 20, hal::UdpStamp::kDrain);
  ASSERT_TRUE(opened.receiver) << opened.error;
  RoundRoom room(opened.receiver->port());
  // The goal as chosen while the robot still stands (once ACTIVE the controller moves it, and the
  // scripted person, fixed relative to the tracker's source, moves with it).
  std::optional<core::Stamped<firmware::CompanionGoal>> g;
  DaemonWithBase d(
      [&](Nanos now, DaemonWithBase& w) {
        if (now == 0ms) person_ahead(w.tracker);  // 1.2 m ahead, 0.3 m right, facing forward
        room.step(now);
        const auto safety = w.daemon.safety().read();
        if (!safety || safety->value.state != core::SafetyState::kActive) {
          g = w.daemon.goal().read();
        }
      },
      true);
  d.daemon.attach_lidar(std::move(opened.receiver));
  d.run_until(1500ms);
  ASSERT_TRUE(g);
  ASSERT_EQ(g->value.status, core::GoalStatus::kOk) << core::to_string(g->value.status);
  EXPECT_EQ(g->value.points, 64);
  EXPECT_EQ(g->value.free_points, 64U) << "a 3 m room leaves the whole ellipse free";
  // On the ellipse around the person: (x - 1.2)^2 / a^2 + (y + 0.3)^2 / b^2 = 1.
  const double ex = (g->value.goal_base.x_m - 1.2) / 1.0;
  const double ey = (g->value.goal_base.y_m + 0.3) / 0.7;
  EXPECT_NEAR(ex * ex + ey * ey, 1.0, 0.02);
  // The objective (alpha 1, beta 0.5) prefers the side point closest to the robot: behind the
  // person, toward the robot.
  EXPECT_LT(g->value.goal_base.x_m, 1.2);
  EXPECT_NE(d.daemon.status_line().find("| goal objective behind"), std::string::npos)
      << d.daemon.status_line();
}

namespace {
// The daemon (tracker, base and the round room's lidar) with `config` until `until`; `each` runs
// at every world step, before the room's (it sets the person's pose and reads the goal).
void run_in_round_room(const firmware::DaemonConfig& config, Nanos until,
                       const std::function<void(Nanos, DaemonWithBase&)>& each) {
  auto opened = hal::UdpReceiver::open({"127.0.0.1", 0}, 4 << 20, hal::UdpStamp::kDrain);
  ASSERT_TRUE(opened.receiver) << opened.error;
  RoundRoom room(opened.receiver->port());
  DaemonWithBase d(
      [&](Nanos now, DaemonWithBase& w) {
        each(now, w);
        room.step(now);
      },
      true, config);
  d.daemon.attach_lidar(std::move(opened.receiver));
  d.run_until(until);
}
}  // namespace

TEST(DaemonWithTrackerAndLidar, TheSwitchCostCountsFromThePointChosenLast) {
  // The person 1.2 m ahead and 0.3 m right, then (at 1 s) 0.3 m left: G's argmin moves to the
  // mirror point. With objective.switch_cost the daemon passes the point it chose last to the
  // selector, so a large cost keeps that point while it stays free.
  const auto indices = [](double switch_cost) {
    firmware::DaemonConfig config = defaults();
    config.objective.switch_cost = switch_cost;
    std::array<int, 2> seen{-1, -1};
    run_in_round_room(config, 1500ms, [&](Nanos now, DaemonWithBase& w) {
      if (now == 0ms) person_ahead(w.tracker);
      if (now == 1000ms) w.tracker.set_sensor_pose(-1.2, -0.3, 0.0, std::numbers::pi);
      const auto g = w.daemon.goal().read();
      const bool ok = g && g->value.status == core::GoalStatus::kOk;
      if (now == 950ms && ok) seen[0] = g->value.index;
      if (now == 1500ms && ok) seen[1] = g->value.index;
    });
    return seen;
  };
  const auto paper = indices(0.0);
  ASSERT_GE(paper[0], 0) << "a goal before the person moves";
  ASSERT_GE(paper[1], 0);
  EXPECT_EQ(paper[1], 64 - paper[0]) << "G alone: the mirror point";
  const auto kept = indices(1000.0);
  EXPECT_EQ(kept[0], paper[0]) << "the first choice has no previous point to count from";
  EXPECT_EQ(kept[1], kept[0]) << "kept: switching costs more than any difference in G";
}

TEST(DaemonWithTrackerAndLidar, TheSlewStepsTheObjectivesPointRoundTheEllipse) {
  // As above: at 1 s the person moves to the robot's other side and G's argmin to the mirror
  // point. Without objective.slew_points_per_s the goal jumps there at once; with 30 points a
  // second (the policy task's 30 Hz: a point an update) it steps there one point at a time.
  const auto goals = [](double slew_points_per_s) {
    firmware::DaemonConfig config = defaults();
    config.objective.slew_points_per_s = slew_points_per_s;
    std::vector<std::pair<int, Nanos>> seen;  // each new goal's index and stamp from 950 ms on
    Nanos last_stamp{-1};
    run_in_round_room(config, 2500ms, [&](Nanos now, DaemonWithBase& w) {
      if (now == 0ms) person_ahead(w.tracker);
      if (now == 1000ms) w.tracker.set_sensor_pose(-1.2, -0.3, 0.0, std::numbers::pi);
      const auto g = w.daemon.goal().read();
      if (now >= 950ms && g && g->stamp != last_stamp && g->value.status == core::GoalStatus::kOk) {
        seen.emplace_back(g->value.index, g->stamp);
        last_stamp = g->stamp;
      }
    });
    return seen;
  };
  const auto wrapped = [](int a, int b) {
    const int k = std::abs(a - b) % 64;
    return std::min(k, 64 - k);
  };
  const auto jump = goals(0.0);
  ASSERT_GE(jump.size(), 30U);
  const int before = jump.front().first;
  const int after = jump.back().first;
  ASSERT_GE(wrapped(before, after), 4) << "the argmin moves by several points";
  int largest = 0;
  for (size_t k = 1; k < jump.size(); ++k)
    largest = std::max(largest, wrapped(jump[k - 1].first, jump[k].first));
  EXPECT_GE(largest, 4) << "without the slew: at once";
  const auto slewed = goals(30.0);
  ASSERT_GE(slewed.size(), 30U);
  EXPECT_EQ(slewed.front().first, before);
  EXPECT_EQ(slewed.back().first, after) << "it gets there";
  for (size_t k = 1; k < slewed.size(); ++k) {
    // The world step that reads the goal may see every second update: a point per update.
    const auto updates =
        std::llround(core::to_seconds(slewed[k].second - slewed[k - 1].second) * 30);
    EXPECT_LE(wrapped(slewed[k - 1].first, slewed[k].first), updates) << "goal " << k;
  }
}

TEST(DaemonWithTrackerAndLidar, TurnInsideKeepsThePointOffTheSideThePersonTurnsTo) {
  // The person 1.2 m ahead and 0.3 m right, turning left on the spot at 1 rad/s from 0.5 s: the
  // robot is behind them and to their left, where G's argmin is. With objective.turn_inside the
  // daemon passes the person's estimated turn rate to W, and a large weight moves q^d off their
  // left (the inside of the turn).
  const auto index_at_1s = [](double turn_inside) {
    firmware::DaemonConfig config = defaults();
    config.objective.turn_inside = turn_inside;
    int seen = -1;
    run_in_round_room(config, 1000ms, [&](Nanos now, DaemonWithBase& w) {
      const double heading = now > 500ms ? core::to_seconds(now - 500ms) * 1.0 : 0.0;
      w.tracker.set_sensor_pose(-1.2, 0.3, 0.0, std::numbers::pi + heading);
      const auto g = w.daemon.goal().read();
      if (now == 1000ms && g && g->value.status == core::GoalStatus::kOk) seen = g->value.index;
    });
    return seen;
  };
  const int paper = index_at_1s(0.0);
  EXPECT_GT(paper, 16) << "behind-left: toward the robot";
  EXPECT_LT(paper, 32);
  const int turning = index_at_1s(1000.0);
  EXPECT_TRUE(turning == 0 || turning >= 32) << turning << ": not on the person's left";
}

TEST(Daemon, SideOfPersonNamesTheDesignPointsAngle) {
  EXPECT_STREQ(firmware::side_of_person(0, 64), "front");
  EXPECT_STREQ(firmware::side_of_person(16, 64), "left");
  EXPECT_STREQ(firmware::side_of_person(32, 64), "behind");
  EXPECT_STREQ(firmware::side_of_person(48, 64), "right");
  EXPECT_STREQ(firmware::side_of_person(63, 64), "front");
  EXPECT_STREQ(firmware::side_of_person(-1, 64), "-");
}

TEST(DaemonWithTrackerAndLidar, ALoadedPolicyChoosesAmongTheFreePoints) {
  // A tiny policy with the real layout (n = 64, 716 inputs) whose output bias prefers point 40
  // (to the person's right-behind); the daemon reports it as the active selector.
  core::PolicyFile p;
  p.layout_id = core::kObservationLayout;
  p.points = 64;
  const auto in = static_cast<Eigen::Index>(core::observation_size(64));
  p.mean = Eigen::VectorXf::Zero(in);
  p.stddev = Eigen::VectorXf::Ones(in);
  core::DenseLayer hidden;
  hidden.weights = Eigen::MatrixXf::Zero(4, in);
  hidden.bias = Eigen::VectorXf::Zero(4);
  hidden.activation = core::Activation::kRelu;
  core::DenseLayer out;
  out.weights = Eigen::MatrixXf::Zero(64, 4);
  out.bias = Eigen::VectorXf::Zero(64);
  out.bias[40] = 5.0f;
  p.layers = {hidden, out};
  // Through the real file format and loader.
  const auto loaded = core::parse_policy(core::encode_policy(p), core::kObservationLayout, 64,
                                         static_cast<uint32_t>(in));
  ASSERT_TRUE(loaded.policy) << loaded.error;

  // Stamped at the drain: the test runs on the simulated clock.
  auto opened = hal::UdpReceiver::open({"127.0.0.1", 0}, 4 << 20, hal::UdpStamp::kDrain);
  ASSERT_TRUE(opened.receiver) << opened.error;
  RoundRoom room(opened.receiver->port());
  DaemonWithBase d(
      [&](Nanos now, DaemonWithBase& w) {
        if (now == 0ms) person_ahead(w.tracker);
        room.step(now);
      },
      true);
  d.daemon.attach_lidar(std::move(opened.receiver));
  d.daemon.attach_policy(*loaded.policy);
  d.run_until(1500ms);
  const auto g = d.daemon.goal().read();
  ASSERT_TRUE(g);
  ASSERT_EQ(g->value.status, core::GoalStatus::kOk);
  EXPECT_STREQ(g->value.selector, "policy");
  EXPECT_EQ(g->value.index, 40);
  EXPECT_NE(d.daemon.status_line().find("| goal policy behind-right"), std::string::npos)
      << d.daemon.status_line();
}

// The machine-readable status: one JSON object with stable keys, written atomically each second.
TEST(Daemon, WritesTheStatusFileAsJsonWithTheDocumentedKeys) {
  const std::string path = ::testing::TempDir() + "companion-status.json";
  std::remove(path.c_str());
  SimDaemon d(defaults());
  d.daemon.set_status_file(path);
  d.run_until(2500ms);
  std::ifstream f(path);
  ASSERT_TRUE(f) << "written";
  const auto j = nlohmann::json::parse(f);
  EXPECT_EQ(j["safety"]["state"], "HOLD");
  EXPECT_EQ(j["safety"]["reason"], "tracker_silent");
  EXPECT_EQ(j["safety"]["reason_code"], 11);
  EXPECT_FALSE(j["safety"]["motion_allowed"].get<bool>());
  ASSERT_EQ(j["tasks"].size(), firmware::task_table().size());
  for (const auto& t : j["tasks"]) {
    if (t["name"] == "control") {
      EXPECT_DOUBLE_EQ(t["rate_hz"].get<double>(), 100.0);
      EXPECT_EQ(t["nominal_hz"], 100);
      EXPECT_EQ(t["overruns"], 0);
    }
  }
  EXPECT_EQ(j["control"]["tracking"], false) << "holding: nothing tracked";
  EXPECT_TRUE(j["goal"]["x_base_m"].is_number());
  EXPECT_TRUE(j["goal"]["held"].is_boolean());
  EXPECT_EQ(d.daemon.status_json(), nlohmann::json::parse(d.daemon.status_json()).dump() + "\n");
}

TEST(Daemon, AnUnwritableStatusFileIsWarnedOnceAndTheDaemonRunsOn) {
  auto ring = std::make_shared<spdlog::sinks::ringbuffer_sink_mt>(1000);
  auto previous = spdlog::default_logger();
  spdlog::set_default_logger(std::make_shared<spdlog::logger>("capture", ring));
  SimDaemon d(defaults());
  d.daemon.set_status_file("/nonexistent-dir/status.json");
  d.run_until(3500ms);
  spdlog::set_default_logger(previous);
  int warnings = 0;
  for (const auto& line : ring->last_formatted()) {
    if (line.find("status: cannot write /nonexistent-dir/status.json") != std::string::npos) {
      ++warnings;
    }
  }
  EXPECT_EQ(warnings, 1);
  EXPECT_EQ(d.daemon.command().read()->count, 351U) << "the control task kept running";
}
