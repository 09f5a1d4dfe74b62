// The real-time sim mode's threads (the main job): the task table on its rate-group threads and
// the world on its own, on the real clock, sharing only the devices' links and the daemon's
// channels. Run under ThreadSanitizer (`make test`): any data race fails it.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "firmware/config/config_loader.hpp"
#include "firmware/daemon.hpp"
#include "firmware/task_table.hpp"
#include "hal/linux_clock.hpp"
#include "sim/sim_run.hpp"
#include "sim/world_thread.hpp"

using namespace std::chrono_literals;

namespace {
// Waits for `done` (checked every 10 ms) up to `limit`: a condition with a timeout, not a delay.
template <typename F>
bool wait_for(F done, std::chrono::milliseconds limit) {
  const auto end = std::chrono::steady_clock::now() + limit;
  while (!done()) {
    if (std::chrono::steady_clock::now() > end) return false;
    std::this_thread::sleep_for(10ms);
  }
  return true;
}
}  // namespace

TEST(SimRealtime, TaskThreadsAndTheWorldThreadRunTogetherAndStopCleanly) {
  firmware::DaemonConfig cfg = *firmware::load_default_config().config;
  cfg.mppi.samples = 256;  // sanitizers slow everything ~10x: keep the loop near its rate
  // This test is about the threads (races, a clean stop), not deadlines: under ThreadSanitizer on
  // a loaded 2-core machine the first control run came 120 ms late and the stall detector
  // latched FAULT. The detector itself is tested on the simulated clock (test_supervisor).
  cfg.supervisor.control_stall_timeout_ms = 2000;
  // Likewise the lidar: one cycle took 1.8 s under ThreadSanitizer with a benchmark on both cores
  // ('lidar silent' held the robot until the person had walked out of reach). Staleness is tested
  // on the simulated clock (test_supervisor, the daemon tests).
  cfg.supervisor.lidar_timeout_ms = 5000;
  cfg.supervisor.costmap_max_age_ms = 5000;
  hal::LinuxClock clock;
  hal::SystemdNotifier notifier;
  firmware::Daemon daemon(cfg, notifier);
  auto scenario = sim::make_scenario("crossing");
  ASSERT_TRUE(scenario);
  sim::WorldThread world(*scenario, sim::world_config(cfg, 1), {}, clock);
  ASSERT_TRUE(daemon.attach_base(world.world().take_base_bus()));
  daemon.attach_tracker(world.world().take_tracker_link());
  daemon.attach_lidar(world.world().take_lidar_source());
  firmware::Executor executor(clock, firmware::group_table(), daemon.bindings());
  daemon.attach(executor);
  const core::Nanos origin = clock.now() + 10ms;
  world.start(origin, daemon);
  executor.start(origin, false);
  daemon.mark_initialized();

  const bool active = wait_for(
      [&] {
        const auto s = daemon.safety().read();
        return s && s->value.state == core::SafetyState::kActive;
      },
      20s);
  EXPECT_TRUE(active) << daemon.status_line();
  EXPECT_TRUE(wait_for([&] { return !daemon.status_json().empty(); }, 5s));
  daemon.request_shutdown();
  EXPECT_TRUE(wait_for([&] { return daemon.shutdown_complete(); }, 5s)) << daemon.status_line();
  executor.stop();
  world.stop();
  EXPECT_EQ(world.world().base().velocity().vx_mps, 0.0);
  EXPECT_GT(world.time_s(), 1.0);
  EXPECT_GT(world.samples().size(), 10U);
}
