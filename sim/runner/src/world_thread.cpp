#include "sim/world_thread.hpp"

#include <cmath>

#include "sim/sim_run.hpp"

namespace sim {

WorldThread::WorldThread(Scenario scenario, const SimWorldConfig& config,
                         const MetricsConfig& metrics, hal::Clock& clock)
    : clock_(clock), world_(std::move(scenario), config, clock), recorder_(metrics) {}

WorldThread::~WorldThread() {
  stop();
}

void WorldThread::start(hal::Nanos origin, const firmware::Daemon& daemon) {
  thread_ = std::thread([this, origin, &daemon] { run(origin, daemon); });
}

void WorldThread::stop() {
  stop_.store(true, std::memory_order_release);
  clock_.interrupt();
  if (thread_.joinable()) thread_.join();
}

void WorldThread::run(hal::Nanos origin, const firmware::Daemon& daemon) {
  hal::ClockThreadGuard guard(clock_);
  const double step_s = world_.config().step_s;
  const hal::Nanos step(static_cast<int64_t>(std::llround(step_s * 1e9)));
  hal::Nanos next = origin;
  while (!stop_.load(std::memory_order_acquire)) {
    if (!clock_.sleep_until(next)) continue;  // interrupted: re-check stop
    const hal::Nanos now = clock_.now();
    // The world's own time starts at `origin`; the devices see the clock's time.
    world_.step(now);
    const core::Pose2 robot = world_.robot_pose();
    const core::Pose2 person = world_.person_pose();
    recorder_.record(world_.time_s(), step_s, robot, person, world_.pedestrian_positions(),
                     world_.footprint_clearance_static(), world_.footprint_clearance_people(),
                     daemon_view(daemon));
    t_s_.store(world_.time_s(), std::memory_order_relaxed);
    distance_m_.store(std::hypot(robot.x_m - person.x_m, robot.y_m - person.y_m),
                      std::memory_order_relaxed);
    next += step;
    if (clock_.now() > next) {
      // Late by more than a step: count it and skip ahead (the world steps in fixed increments
      // and catches up inside step()).
      overruns_.fetch_add(1, std::memory_order_relaxed);
      while (next < clock_.now())
        next += step;
    }
  }
}

}  // namespace sim
