#include "sim_mode.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cmath>
#include <iostream>

#include "firmware/daemon.hpp"
#include "sim/pedestrian_dataset.hpp"
#include "sim/sim_run.hpp"

namespace companiond {

bool uses_sim(const firmware::DaemonConfig& cfg) {
  return cfg.devices.tracker == "sim" || cfg.devices.lidar == "sim" || cfg.devices.base == "sim";
}

std::optional<sim::Scenario> build_scenario(const SimOptions& o, std::string& error) {
  if (!o.pedestrians_file.empty()) {
    const sim::DatasetLoad loaded =
        sim::load_pedestrian_dataset(o.pedestrians_file, o.frame_period_s);
    if (!loaded.ok) {
      error = loaded.error;
      return std::nullopt;
    }
    int id = o.follow_id;
    if (id < 0) id = sim::longest_walk(loaded.data);
    auto s = sim::recorded_scenario(loaded.data, id, &error);
    if (s) s->name = fmt::format("{} (person {})", o.pedestrians_file, id);
    return s;
  }
  auto s = sim::make_scenario(o.scenario, o.seed);
  if (!s) {
    error = fmt::format("unknown scenario '{}'; built-in:", o.scenario);
    for (const auto& info : sim::builtin_scenarios())
      error += fmt::format(" {}", info.name);
  }
  return s;
}

int run_on_sim_clock(const firmware::DaemonConfig& cfg, const SimOptions& o,
                     const sim::Scenario& scenario, double duration_s) {
  sim::SimRunOptions ro;
  ro.config = cfg;
  ro.scenario = scenario;
  ro.seed = o.seed;
  ro.duration_s = duration_s;
  ro.quiet = false;
  spdlog::info("simulated clock: '{}' for {:.1f} s", scenario.name,
               duration_s > 0 ? duration_s : scenario.duration_s);
  const sim::SimRunResult r = sim::run_simulation(ro);
  const auto& m = r.metrics;
  std::cout << fmt::format(
      "{}: {}{} | {:.1f} s simulated in {:.1f} s | UT {:.2f} s | RMSE e_x {:.3f} m e_y {:.3f} m "
      "e_theta {:.3f} rad | person {:.2f}..{:.2f} m | control p99 {:.2f} ms\n",
      scenario.name, m.success ? "SUCCESS" : "FAILURE", m.success ? "" : " (" + m.failure + ")",
      m.duration_s, r.wall_s, m.uncomfortable_s, m.rmse_ex_m, m.rmse_ey_m, m.rmse_etheta_rad,
      m.min_person_distance_m, m.max_person_distance_m, sim::quantile(r.control_ms, 0.99));
  if (!o.report_dir.empty()) {
    sim::RunReportInputs in;
    in.scenario = &scenario;
    in.metrics = &r.metrics;
    in.samples = &r.samples;
    in.policy_ms = r.policy_ms;
    in.control_ms = r.control_ms;
    in.title = fmt::format("companiond on '{}' (simulated clock, seed {})", scenario.name, o.seed);
    in.notes = r.final_status;
    const std::string err = sim::write_run_report(o.report_dir, in);
    if (!err.empty()) {
      std::cerr << "report: " << err << "\n";
      return 1;
    }
    std::cout << "report: " << o.report_dir << "/report.md, picture " << o.report_dir
              << "/trajectory.svg\n";
  }
  return m.success ? 0 : 3;
}

std::string live_line(const firmware::Daemon& daemon, const sim::WorldThread* world) {
  std::string s;
  if (world != nullptr) s += fmt::format("[{:6.1f} s] ", world->time_s());
  const auto safety = daemon.safety().read();
  if (!safety) return s + "starting";
  s += core::state_name(safety->value.state);
  if (safety->value.reason != core::Reason::kNone) {
    s += fmt::format(" ({})", core::reason_text(safety->value.reason));
  }
  if (const auto g = daemon.goal().read(); g && g->value.status == core::GoalStatus::kOk) {
    s += fmt::format(" | {} {}", g->value.selector,
                     firmware::side_of_person(g->value.index, g->value.points));
  } else if (g) {
    s += fmt::format(" | goal: {}", core::to_string(g->value.status));
  }
  if (world != nullptr) s += fmt::format(" | person {:.2f} m", world->person_distance_m());
  if (const auto t = daemon.tracker_health().read()) {
    s += fmt::format(" | tracker {} {:.0f}Hz", core::confidence_name(t->value.confidence),
                     t->value.rate_hz);
    if (t->value.decode_errors + t->value.dropped_frames > 0) {
      s += fmt::format(" err {}", t->value.decode_errors + t->value.dropped_frames);
    }
  }
  if (const auto c = daemon.control_status().read()) {
    s += fmt::format(" | cmd {:+.2f} {:+.2f} {:+.2f}", c->value.command.vx_mps,
                     c->value.command.vy_mps, c->value.command.wz_radps);
    if (c->value.failures > 0) s += fmt::format(" mppi-fail {}", c->value.failures);
  }
  const std::string rates = daemon.rates_text();
  if (!rates.empty()) s += " | " + rates;
  return s;
}

void write_report(const std::string& dir, const sim::Scenario& scenario,
                  const sim::WorldThread& world, const std::string& title,
                  const std::string& notes) {
  const sim::RunMetrics m = world.metrics();
  sim::RunReportInputs in;
  in.scenario = &scenario;
  in.metrics = &m;
  in.samples = &world.samples();
  in.title = title;
  in.notes = notes;
  const std::string err = sim::write_run_report(dir, in);
  if (!err.empty()) {
    spdlog::error("report: {}", err);
    return;
  }
  spdlog::info(
      "report: {}: {} (UT {:.2f} s, RMSE e_x {:.3f} e_y {:.3f} e_theta {:.3f}); picture {}",
      dir + "/report.md", m.success ? "SUCCESS" : "FAILURE: " + m.failure, m.uncomfortable_s,
      m.rmse_ex_m, m.rmse_ey_m, m.rmse_etheta_rad, dir + "/trajectory.svg");
}

}  // namespace companiond
