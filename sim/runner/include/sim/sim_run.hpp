#pragma once
// One closed-loop run of the daemon in the simulated world on the simulated clock: the real
// task table (single-threaded, deterministic), the real drivers, the devices' real bytes. Used
// by the integration tests, companion-eval and `companiond --sim-clock`.
#include <functional>
#include <string>
#include <vector>

#include "firmware/config/daemon_config.hpp"
#include "hal/can/can_frame.hpp"
#include "sim/run_metrics.hpp"
#include "sim/scenario.hpp"
#include "sim/sim_world.hpp"

namespace firmware {
class Daemon;
}

namespace sim {

// The simulator's settings that must match the daemon's configuration (sensor mounts, the
// robot's footprint and limits), taken from it.
SimWorldConfig world_config(const firmware::DaemonConfig& cfg, uint32_t seed);

// What the daemon decided, read from its channels (q^d as the point of the person's W it chose).
DaemonView daemon_view(const firmware::Daemon& daemon);

struct SimRunOptions {
  firmware::DaemonConfig config;
  Scenario scenario;
  uint32_t seed = 1;
  double duration_s = 0;  // 0: the scenario's
  // Called every world step (5 ms) before the world advances: fault injection, observation.
  std::function<void(double t_s, SimWorld& world, firmware::Daemon& daemon)> script;
  bool capture_can = false;          // keep every CAN frame the daemon sends
  bool quiet = true;                 // daemon logs at warning level and above only
  bool person_avoids_robot = true;   // SimWorldConfig::person_avoids_robot
  bool replayed_avoid_robot = true;  // SimWorldConfig::replayed_avoid_robot
  double person_sway_rad = 0;        // SimWorldConfig::person_sway_rad
  double sample_period_s = 0.1;      // SimRunResult::samples (world steps are 5 ms)
  // The daemon's costmap at these times (s), written as map_server maps STEM-t<time>.pgm/.yaml
  // with what the daemon knew then (sim/costmap_snapshot.hpp): to see why a trial went wrong.
  std::vector<double> costmap_at_s;
  std::string costmap_stem;
};

// The control task's counters at the end of a run (firmware::ControlStatus): how often the
// controller's safety layers and structured samples acted, per trial.
struct ControllerCounts {
  uint64_t steps = 0;               // controller runs (MPPI or the PID follower)
  uint64_t failures = 0;            // MPPI runs that failed numerically
  uint64_t repairs = 0;             // first controls the DCBF QP repair changed
  uint64_t closing_limits = 0;      // commands the closing-speed limit slowed
  uint64_t guided_plans = 0;        // a structured sample was the plan
  uint64_t paths_planned = 0;       // a costmap path was planned (mppi.path_guide)
  uint64_t path_guided_plans = 0;   // ... and following it was the plan
  uint64_t orbits_planned = 0;      // q^d across the person: orbit samples ran (orbit_guide)
  uint64_t orbit_guided_plans = 0;  // ... and one was the plan
  uint64_t obstacle_limits = 0;     // commands the obstacle speed limit slowed
};

struct SimRunResult {
  RunMetrics metrics;
  std::vector<RunSample> samples;
  std::vector<double> policy_ms;   // wall time of every policy-task run
  std::vector<double> control_ms;  // wall time of every control-task run
  std::vector<hal::CanFrame> can_out;
  ControllerCounts controller;
  std::string final_status;
  double wall_s = 0;
};

SimRunResult run_simulation(const SimRunOptions& options);

}  // namespace sim
