#pragma once
// companiond with `sim` devices: the simulated world of sim/ stands in for the robot's devices
// and speaks their wire formats to the daemon's drivers. Real time (a world thread beside the
// task table) or the simulated clock (--sim-clock: single-threaded, deterministic, as fast as
// the CPU allows). Either way a run report can be written at the end.
#include <optional>
#include <string>

#include "firmware/config/daemon_config.hpp"
#include "sim/run_report.hpp"
#include "sim/scenario.hpp"
#include "sim/world_thread.hpp"

namespace firmware {
class Daemon;
}

namespace companiond {

struct SimOptions {
  std::string scenario = "static_obstacle";
  uint32_t seed = 1;
  std::string pedestrians_file;  // recorded pedestrians (frame id x y)
  double frame_period_s = 0.4;
  int follow_id = -1;  // -1: the recorded person who walks the farthest
  bool sim_clock = false;
  std::string report_dir;
};

bool uses_sim(const firmware::DaemonConfig& cfg);
std::optional<sim::Scenario> build_scenario(const SimOptions& o, std::string& error);
// The simulated clock: runs the scenario, prints the summary, writes the report. Exit code.
int run_on_sim_clock(const firmware::DaemonConfig& cfg, const SimOptions& o,
                     const sim::Scenario& scenario, double duration_s);
// One line for a terminal: state, selector and side, distance, errors, rates.
std::string live_line(const firmware::Daemon& daemon, const sim::WorldThread* world);
// The report of a real-time run.
void write_report(const std::string& dir, const sim::Scenario& scenario,
                  const sim::WorldThread& world, const std::string& title,
                  const std::string& notes);

}  // namespace companiond
