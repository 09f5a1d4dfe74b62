#pragma once
// The simulated world on its own thread, in real time: steps the world every config.step_s on the
// given clock (absolute deadlines, like the daemon's tasks) and records the run's metrics from the
// truth and the daemon's channels. For `companiond` with `sim` devices (the main job).
#include <atomic>
#include <memory>
#include <mutex>
#include <thread>

#include "hal/clock.hpp"
#include "sim/run_metrics.hpp"
#include "sim/sim_world.hpp"

namespace firmware {
class Daemon;
}

namespace sim {

class WorldThread {
 public:
  WorldThread(Scenario scenario, const SimWorldConfig& config, const MetricsConfig& metrics,
              hal::Clock& clock);
  ~WorldThread();
  WorldThread(const WorldThread&) = delete;
  WorldThread& operator=(const WorldThread&) = delete;

  SimWorld& world() { return world_; }  // before start(): take the device ends
  // Starts stepping at `origin` (the world's t = 0); the daemon is read for the metrics.
  void start(hal::Nanos origin, const firmware::Daemon& daemon);
  void stop();

  // Live values (any thread).
  [[nodiscard]] double time_s() const { return t_s_.load(std::memory_order_relaxed); }
  [[nodiscard]] double person_distance_m() const {
    return distance_m_.load(std::memory_order_relaxed);
  }
  [[nodiscard]] uint64_t overruns() const { return overruns_.load(std::memory_order_relaxed); }

  // After stop().
  [[nodiscard]] RunMetrics metrics() const { return recorder_.finish(); }
  [[nodiscard]] const std::vector<RunSample>& samples() const { return recorder_.samples(); }

 private:
  void run(hal::Nanos origin, const firmware::Daemon& daemon);

  hal::Clock& clock_;
  SimWorld world_;
  RunMetricsRecorder recorder_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<double> t_s_{0};
  std::atomic<double> distance_m_{0};
  std::atomic<uint64_t> overruns_{0};
};

}  // namespace sim
