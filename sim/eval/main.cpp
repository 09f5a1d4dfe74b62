// companion-eval: the paper's comparison, reproducibly. Runs the daemon (real task table, real
// drivers, the devices' real bytes) in the simulated world on the simulated clock, one trial per
// core at a time, for every case and method asked for, and writes one CSV row per trial and the
// tables (Markdown) in the layout of the paper. Metric definitions: sim/runner/run_metrics.hpp.
//
//   companion-eval --case paper --trials 50 --out eval/          # scenarios 1-7, all methods
//   companion-eval --case crowds --method objective              # crowd densities 5/10/15/20
//   companion-eval --pedestrians sim/data/pedestrians/biwi_hotel.txt --frame-period 0.4 --follow 38
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <mutex>
#include <numbers>
#include <thread>

#include "eval_plan.hpp"
#include "firmware/config/config_loader.hpp"
#include "firmware/daemon.hpp"
#include "firmware/tool_console.hpp"
#include "sim/pedestrian_dataset.hpp"
#include "sim/run_report.hpp"
#include "sim/sim_run.hpp"

namespace {

struct Outcome {
  eval::Trial trial;
  sim::RunMetrics m;
  double policy_p50_ms = 0, policy_p99_ms = 0, control_p50_ms = 0, control_p99_ms = 0;
  std::vector<double> control_ms;
  std::vector<double> policy_ms;
  double wall_s = 0;
  sim::ControllerCounts controller;
};

struct MeanStd {
  double mean = 0, std = 0;
  int n = 0;
};
MeanStd mean_std(const std::vector<double>& v) {
  MeanStd r;
  r.n = static_cast<int>(v.size());
  if (v.empty()) return r;
  for (double x : v)
    r.mean += x / static_cast<double>(v.size());
  for (double x : v)
    r.std += (x - r.mean) * (x - r.mean) / static_cast<double>(v.size());
  r.std = std::sqrt(r.std);
  return r;
}
std::string pm(const MeanStd& s, const char* fmt_one) {
  if (s.n == 0) return "-";
  return fmt::format(fmt::runtime(std::string(fmt_one) + " ± " + fmt_one), s.mean, s.std);
}

std::string csv_header() {
  return "case,method,seed,scenario,success,failure,collision,duration_s,active_s,uncomfortable_s,"
         "inside_ellipse_s,rmse_ex_m,rmse_ey_m,rmse_etheta_rad,min_person_distance_m,"
         "mean_person_distance_m,max_person_distance_m,longest_far_s,min_static_clearance_m,"
         "min_people_clearance_m,rms_jerk_mps3,stops,side_front,side_front_left,side_left,"
         "side_behind_left,side_behind,side_behind_right,side_right,side_front_right,"
         "policy_p50_ms,policy_p99_ms,control_p50_ms,control_p99_ms,wall_s,"
         "control_steps,control_failures,qp_repairs,closing_limits,guided_plans,paths_planned,"
         "path_guided_plans,orbits_planned,orbit_guided_plans,obstacle_limits\n";
}

std::string csv_row(const Outcome& o, const std::string& scenario) {
  const auto& m = o.m;
  std::string failure = m.failure;
  std::replace(failure.begin(), failure.end(), ',', ';');
  std::string sides;
  for (double t : m.side_time_s)
    sides += fmt::format(",{:.2f}", t);
  return fmt::format(
      "{},{},{},{},{},{},{},{:.2f},{:.2f},{:.3f},{:.3f},{:.4f},{:.4f},{:.4f},{:.3f},{:.3f},{:.3f},"
      "{:.2f},{:.3f},{:.3f},{:.2f},{}{},{:.4f},{:.4f},{:.4f},{:.4f},{:.2f},{},{},{},{},{},{},{},{},"
      "{},{}\n",
      o.trial.c->name, o.trial.method->name, o.trial.seed, scenario, m.success ? 1 : 0, failure,
      m.collision ? 1 : 0, m.duration_s, m.active_s, m.uncomfortable_s, m.inside_ellipse_s,
      m.rmse_ex_m, m.rmse_ey_m, m.rmse_etheta_rad, m.min_person_distance_m,
      m.mean_person_distance_m, m.max_person_distance_m, m.longest_far_s,
      std::min(m.min_static_clearance_m, 999.0), std::min(m.min_people_clearance_m, 999.0),
      m.rms_jerk, m.stops, sides, o.policy_p50_ms, o.policy_p99_ms, o.control_p50_ms,
      o.control_p99_ms, o.wall_s, o.controller.steps, o.controller.failures, o.controller.repairs,
      o.controller.closing_limits, o.controller.guided_plans, o.controller.paths_planned,
      o.controller.path_guided_plans, o.controller.orbits_planned, o.controller.orbit_guided_plans,
      o.controller.obstacle_limits);
}

std::string causes_text(const std::map<std::string, int>& causes) {
  std::string out;
  for (const auto& [kind, count] : causes)
    out += fmt::format("{}{} {}", out.empty() ? "" : ", ", kind, count);
  return out.empty() ? "-" : out;
}

// The paper's crowd-density table: SR, UT and mean planning time against the number of
// pedestrians, one row per method and density.
std::string crowd_table(const std::vector<eval::Case>& cases,
                        const std::vector<eval::Method>& methods,
                        const std::vector<Outcome>& outcomes) {
  std::string md;
  for (const auto& m : methods) {
    for (const auto& c : cases) {
      if (c.name.rfind("crowd-", 0) != 0) continue;
      int ok = 0, n = 0;
      std::vector<double> ut, ctl;
      for (const Outcome& o : outcomes) {
        if (o.trial.c != &c || o.trial.method->name != m.name) continue;
        ++n;
        ok += o.m.success ? 1 : 0;
        ut.push_back(o.m.uncomfortable_s);
        ctl.insert(ctl.end(), o.control_ms.begin(), o.control_ms.end());
      }
      if (n == 0) continue;
      if (md.empty()) {
        md = "\n## crowd density\n\n| method | pedestrians | trials | SR % | UT s | mean control "
             "step ms |\n|---|---|---|---|---|---|\n";
      }
      md += fmt::format("| {} | {} | {} | {:.0f} | {} | {:.2f} |\n", m.name, c.random.pedestrians,
                        n, 100.0 * ok / n, pm(mean_std(ut), "{:.2f}"), mean_std(ctl).mean);
    }
  }
  return md;
}

int run(int argc, char** argv) {
  CLI::App app{
      "companion-eval: the paper's tables from the simulated world (reference/evaluation.md)"};
  std::vector<std::string> case_names{"paper"};
  std::vector<std::string> method_names{"objective", "fixed_behind", "fixed_side", "pid"};
  int trials = 50;
  uint32_t seed = 1;
  unsigned jobs = std::max(1U, std::thread::hardware_concurrency());
  std::string out_dir = "eval-out";
  std::string config_path;
  std::string pedestrians;
  double frame_period = 0.4;
  int follow = -1;
  double duration_s = 0;
  bool samples = false;
  app.add_option("--case", case_names,
                 "cases: open static_obstacle pedestrian_front_right corridor doorway crossing "
                 "random dead_end | paper crowds speeds sizes constrained | crowd-N speed-V "
                 "size-AxB clutter-C turns-D[xR]")
      ->delimiter(',');
  app.add_option("--method", method_names,
                 "methods: objective fixed_behind fixed_side pid policy (policy needs a policy "
                 "file: policy.file or --policy-file)")
      ->delimiter(',');
  app.add_option("--trials", trials, "trials of the random and dead_end cases (paper: 50)")
      ->check(CLI::Range(1, 100000));
  app.add_option("--seed", seed, "first seed (trial i uses seed + i)");
  app.add_option("--jobs", jobs, "trials in parallel (default: the cores)")
      ->check(CLI::Range(1U, 256U));
  app.add_option("--out", out_dir, "output directory (trials.csv, summary.md)");
  app.add_option("-c,--config", config_path, "daemon configuration (default: built-in defaults)");
  std::string policy_file;
  app.add_option("--policy-file", policy_file,
                 "the learned selector's file for every trial (sets policy.file over --config's)");
  app.add_option("--pedestrians", pedestrians,
                 "recorded pedestrians (frame id x y) to follow through");
  app.add_option("--frame-period", frame_period, "seconds between consecutive frame values")
      ->check(CLI::PositiveNumber);
  app.add_option("--follow", follow, "recorded person to accompany (default: who walks farthest)");
  int walkers = 1;
  app.add_option("--walkers", walkers,
                 "with --pedestrians: accompany each of the N people who walk farthest, one "
                 "trial each (trial i the i-th farthest, seed + i)")
      ->check(CLI::Range(1, 10000));
  app.add_option("--duration-s", duration_s, "cut every trial to this long (0: the scenario's)")
      ->check(CLI::NonNegativeNumber);
  app.add_flag("--samples", samples,
               "also write each trial's samples (every --sample-period-s) for the plots");
  double sample_period_s = 0.1;
  app.add_option("--sample-period-s", sample_period_s,
                 "seconds between samples (default 0.1; 0.01 to see the 100 Hz control's "
                 "answer to a turn: sim/eval/turn_lag.py)")
      ->check(CLI::Range(0.005, 10.0));
  bool daemon_log = false;
  app.add_flag("--daemon-log", daemon_log,
               "print the daemons' log (info: every failsafe transition) to diagnose a trial; "
               "use with one trial, or --jobs 1, to keep the lines in order");
  bool person_walks_through = false;
  app.add_flag("--person-walks-through", person_walks_through,
               "the followed person keeps to their script even into the robot (default: they "
               "do not walk into it; contacts the robot causes count either way)");
  bool recorded_walk_through = false;
  app.add_flag("--recorded-walk-through", recorded_walk_through,
               "recorded pedestrians keep to their recording even into the robot (default: "
               "they do not walk into it, as the followed person; the recorded tables up to the "
               "thirty-seventh session)");
  double person_sway_deg = 0;
  app.add_option("--person-sway-deg", person_sway_deg,
                 "the worn sensor sways with the person's gait by this much either side of their "
                 "heading, one cycle per 1.4 m stride (its yaw and gyro; about 4 at the belt or "
                 "chest; default 0)")
      ->check(CLI::Range(0.0, 30.0));
  std::vector<double> costmap_at;
  app.add_option("--costmap-at", costmap_at,
                 "write the daemon's costmap at these times (s) of each trial as map_server maps "
                 "(OUT/costmaps/CASE-METHOD-SEED-tT.pgm/.yaml, with robot, person, q^d and the "
                 "controller's plan costs; draw with sim/eval/plot_costmap.py)")
      ->delimiter(',')
      ->check(CLI::NonNegativeNumber);
  CLI11_PARSE(app, argc, argv);

  auto loaded = config_path.empty() ? firmware::load_default_config()
                                    : firmware::load_config_file(config_path);
  if (!loaded.ok()) {
    for (const auto& e : loaded.errors)
      std::cerr << "config error: " << e.to_string() << "\n";
    return 2;
  }
  if (!policy_file.empty()) loaded.config->policy.file = policy_file;
  // Every trial's daemon loads a configured policy file (the selector decides whether it is
  // used): one that does not load stops here, before any trial, not in a worker.
  if (!loaded.config->policy.file.empty()) {
    const auto policy = firmware::load_configured_policy(*loaded.config);
    if (!policy.policy) {
      std::cerr << "policy.file " << loaded.config->policy.file << ": " << policy.error << "\n";
      return 2;
    }
  }
  std::vector<eval::Method> methods;
  for (const auto& name : method_names) {
    auto m = eval::method_by_name(name);
    if (!m) {
      std::cerr << "unknown method '" << name << "'\n";
      return 2;
    }
    if (m->name == "policy" && loaded.config->policy.file.empty()) {
      std::cerr << "method 'policy' needs a policy file (policy.file in --config, or "
                   "--policy-file)\n";
      return 2;
    }
    methods.push_back(*m);
  }
  std::vector<eval::Case> cases;
  std::vector<sim::Scenario> recorded;  // one per trial of the recorded case
  if (!pedestrians.empty()) {
    const auto ds = sim::load_pedestrian_dataset(pedestrians, frame_period);
    if (!ds.ok) {
      std::cerr << ds.error << "\n";
      return 2;
    }
    if (follow >= 0 && walkers > 1) {
      std::cerr << "--follow names one person; --walkers picks the N who walk farthest\n";
      return 2;
    }
    const std::vector<int> ids =
        follow >= 0 ? std::vector<int>{follow} : sim::longest_walks(ds.data, walkers);
    if (ids.size() < static_cast<size_t>(walkers)) {
      std::cerr << pedestrians << ": " << ids.size() << " people, " << walkers
                << " asked for (--walkers)\n";
      return 2;
    }
    for (const int id : ids) {
      std::string error;
      auto s = sim::recorded_scenario(ds.data, id, &error);
      if (!s) {
        std::cerr << pedestrians << ": " << error << "\n";
        return 2;
      }
      recorded.push_back(std::move(*s));
    }
    cases.push_back(
        eval::Case{"recorded", "recorded", static_cast<int>(recorded.size()), {}, 0, 0});
  } else {
    for (const auto& name : case_names) {
      std::string error;
      auto expanded = eval::expand_cases(name, trials, error);
      if (!expanded) {
        std::cerr << error << "\n";
        return 2;
      }
      cases.insert(cases.end(), expanded->begin(), expanded->end());
    }
  }

  std::vector<eval::Trial> plan;
  for (const auto& c : cases) {
    for (const auto& m : methods) {
      for (int i = 0; i < c.trials; ++i)
        plan.push_back(eval::Trial{&c, &m, seed + static_cast<uint32_t>(i), i});
    }
  }
  std::filesystem::create_directories(out_dir);
  // Trials run quietly; failures are in the results.
  spdlog::set_level(daemon_log ? spdlog::level::info : spdlog::level::err);
  std::cout << fmt::format("companion-eval: {} trials ({} cases x {} methods), {} in parallel\n",
                           plan.size(), cases.size(), methods.size(), jobs);

  std::vector<Outcome> outcomes(plan.size());
  std::atomic<size_t> next{0};
  std::atomic<size_t> done{0};
  std::mutex print_mutex;
  const auto t0 = std::chrono::steady_clock::now();
  auto worker = [&] {
    for (size_t i = next.fetch_add(1); i < plan.size(); i = next.fetch_add(1)) {
      const eval::Trial& t = plan[i];
      sim::SimRunOptions o;
      o.quiet = !daemon_log;
      o.config = eval::trial_config(*loaded.config, *t.c, *t.method);
      o.scenario = recorded.empty() ? eval::make_world(*t.c, t.seed) : recorded.at(t.index);
      o.seed = t.seed;
      o.duration_s = duration_s;
      o.person_avoids_robot = !person_walks_through;
      o.replayed_avoid_robot = !recorded_walk_through;
      o.person_sway_rad = person_sway_deg * std::numbers::pi / 180.0;
      o.sample_period_s = sample_period_s;
      if (!costmap_at.empty()) {
        std::filesystem::create_directories(out_dir + "/costmaps");
        o.costmap_at_s = costmap_at;
        o.costmap_stem =
            fmt::format("{}/costmaps/{}-{}-{}", out_dir, t.c->name, t.method->name, t.seed);
      }
      const sim::SimRunResult r = sim::run_simulation(o);
      Outcome& out = outcomes[i];
      out.trial = t;
      out.m = r.metrics;
      out.wall_s = r.wall_s;
      out.controller = r.controller;
      out.policy_p50_ms = sim::quantile(r.policy_ms, 0.5);
      out.policy_p99_ms = sim::quantile(r.policy_ms, 0.99);
      out.control_p50_ms = sim::quantile(r.control_ms, 0.5);
      out.control_p99_ms = sim::quantile(r.control_ms, 0.99);
      out.policy_ms = r.policy_ms;
      out.control_ms = r.control_ms;
      if (samples) {
        const std::string dir = fmt::format("{}/samples/{}", out_dir, t.c->name);
        std::filesystem::create_directories(dir);
        std::ofstream(fmt::format("{}/{}-{}.csv", dir, t.method->name, t.seed))
            << sim::samples_csv(r.samples);
        // The world's walls and obstacles, for the trajectory plots (one file per trial, as
        // trials of one seed run in parallel).
        std::ofstream(fmt::format("{}/{}-{}-world.csv", dir, t.method->name, t.seed))
            << sim::world_csv(o.scenario.world);
      }
      const size_t n = done.fetch_add(1) + 1;
      const std::scoped_lock lock(print_mutex);
      std::cout << fmt::format("[{}/{}] {} {} seed {}: {}{}\n", n, plan.size(), t.c->name,
                               t.method->name, t.seed, r.metrics.success ? "success" : "FAIL",
                               r.metrics.success ? "" : " (" + r.metrics.failure + ")")
                << std::flush;
    }
  };
  std::vector<std::thread> pool;
  for (unsigned j = 0; j < std::min<size_t>(jobs, plan.size()); ++j)
    pool.emplace_back(worker);
  for (auto& th : pool)
    th.join();
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  std::ofstream csv(out_dir + "/trials.csv");
  csv << csv_header();
  for (const Outcome& o : outcomes) {
    csv << csv_row(o, recorded.empty() ? eval::make_world(*o.trial.c, o.trial.seed).name
                                       : recorded.at(o.trial.index).name);
  }

  // The tables: one per case, the paper's columns, one row per method.
  std::string md = fmt::format(
      "# companion-eval\n\n{} trials in {:.0f} s ({:.1f} trials/min, {} jobs); metrics as defined "
      "in sim/runner/include/sim/run_metrics.hpp.\n",
      plan.size(), wall, 60.0 * static_cast<double>(plan.size()) / wall, jobs);
  for (const auto& c : cases) {
    md += fmt::format("\n## {} ({} trial{} per method)\n\n", c.name, c.trials,
                      c.trials == 1 ? "" : "s");
    md +=
        "| method | SR % | UT s | e_x m | e_y m | e_θ rad | in ellipse s | min dist. person m | "
        "collisions | failures | policy p50 / p99 ms | control p50 / p99 ms |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const auto& m : methods) {
      std::vector<double> ut, ex, ey, et, ell, dmin, ctl, pol;
      int ok = 0, n = 0, collisions = 0;
      std::map<std::string, int> causes;  // the first failure of each failed trial
      for (const Outcome& o : outcomes) {
        if (o.trial.c != &c || o.trial.method->name != m.name) continue;
        ++n;
        ok += o.m.success ? 1 : 0;
        if (!o.m.success) ++causes[sim::to_string(o.m.failure_kind)];
        collisions += o.m.collision ? 1 : 0;
        ut.push_back(o.m.uncomfortable_s);
        ex.push_back(o.m.rmse_ex_m);
        ey.push_back(o.m.rmse_ey_m);
        et.push_back(o.m.rmse_etheta_rad);
        ell.push_back(o.m.inside_ellipse_s);
        dmin.push_back(o.m.min_person_distance_m);
        ctl.insert(ctl.end(), o.control_ms.begin(), o.control_ms.end());
        pol.insert(pol.end(), o.policy_ms.begin(), o.policy_ms.end());
      }
      if (n == 0) continue;
      md += fmt::format(
          "| {} | {:.0f} | {} | {} | {} | {} | {} | {} | {} | {} | {:.3f} / {:.3f} | {:.3f} / "
          "{:.3f} |\n",
          m.name, 100.0 * ok / n, pm(mean_std(ut), "{:.2f}"), pm(mean_std(ex), "{:.3f}"),
          pm(mean_std(ey), "{:.3f}"), pm(mean_std(et), "{:.3f}"), pm(mean_std(ell), "{:.2f}"),
          pm(mean_std(dmin), "{:.2f}"), collisions, causes_text(causes), sim::quantile(pol, 0.5),
          sim::quantile(pol, 0.99), sim::quantile(ctl, 0.5), sim::quantile(ctl, 0.99));
    }
  }
  md += crowd_table(cases, methods, outcomes);
  std::ofstream(out_dir + "/summary.md") << md;
  std::cout << "\n"
            << md << fmt::format("\nwrote {}/trials.csv and {}/summary.md\n", out_dir, out_dir);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return firmware::tool::main_guarded("companion-eval", run, argc, argv);
}
