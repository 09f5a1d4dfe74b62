#include "sim/sim_run.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <thread>

#include "firmware/daemon.hpp"
#include "firmware/task_table.hpp"
#include "hal/sd_notify.hpp"
#include "hal/sim_clock.hpp"
#include "sim/costmap_snapshot.hpp"

namespace sim {

SimWorldConfig world_config(const firmware::DaemonConfig& cfg, uint32_t seed) {
  SimWorldConfig w;
  w.tracker.sensor_tx_id = static_cast<uint8_t>(cfg.tracker.sensor_tx_id);
  w.tracker.seed = seed;
  w.tracker.position_noise_m = 0.01;
  w.tracker.heading_noise_rad = 0.02;
  // A MEMS gyro as it comes: white noise at 120 Hz (about 0.005 rad/s) and an uncalibrated
  // bias of half a degree a second per axis (the daemon reads the gyro with human.use_gyro).
  w.tracker.gyro_noise_dps = 0.3;
  w.tracker.gyro_bias_dps = {0.5, -0.5, 0.5};
  w.tracker_extrinsics = firmware::tracker_extrinsics(cfg);
  w.lidar.seed = seed;
  w.lidar.mount_x_m = cfg.lidar.x_m;
  w.lidar.mount_y_m = cfg.lidar.y_m;
  w.lidar.mount_z_m = cfg.lidar.z_m;
  w.lidar.mount_yaw_rad = cfg.lidar.yaw_rad;
  w.footprint_x_min_m = cfg.costmap.footprint_x_min_m;
  w.footprint_x_max_m = cfg.costmap.footprint_x_max_m;
  w.footprint_y_min_m = cfg.costmap.footprint_y_min_m;
  w.footprint_y_max_m = cfg.costmap.footprint_y_max_m;
  w.base.linear_accel_mps2 = cfg.limits.linear_accel_max_mps2;
  w.base.angular_accel_radps2 = cfg.limits.angular_accel_max_radps2;
  w.base.command_latency = std::chrono::milliseconds(20);  // motor controllers' reaction
  w.base.feedback_noise_rel = 0.02;                        // slip + encoders: odometry drifts
  w.base.seed = seed;
  return w;
}

DaemonView daemon_view(const firmware::Daemon& daemon) {
  DaemonView v;
  const auto s = daemon.safety().read();
  v.active = s && s->value.state == core::SafetyState::kActive;
  const auto g = daemon.goal().read();
  if (g && g->value.status == core::GoalStatus::kOk) {
    v.has_goal = true;
    v.goal_in_person = g->value.goal_in_person();
    v.side = firmware::side_sector(g->value.index, g->value.points);
  }
  if (const auto c = daemon.command().read()) {
    v.cmd_vx = c->value.vx_mps;
    v.cmd_vy = c->value.vy_mps;
    v.cmd_wz = c->value.wz_radps;
  }
  if (const auto t = daemon.human_track().read(); t && t->value.valid) {
    v.has_person_estimate = true;
    v.person_est_theta = t->value.mean_data[2];
    v.person_est_yaw_rate = t->value.mean_data[5];
  }
  if (const auto c = daemon.control_status().read(); c && c->value.tracking) {
    v.tracking = true;
    v.plan_tracking = c->value.best_cost.tracking;
    v.plan_collision = c->value.best_cost.collision;
    v.plan_barrier = c->value.best_cost.barrier;
  }
  return v;
}

namespace {
// Writes the daemon's latest costmap and what it knew at t_s (SimRunOptions::costmap_at_s).
void write_costmap_snapshot(const firmware::Daemon& daemon, const firmware::DaemonConfig& cfg,
                            core::Nanos now, const std::string& stem) {
  const double t_s = core::to_seconds(now);
  const auto map = daemon.costmap().latest();
  if (map->cells() == 0) return;  // none built yet
  CostmapMarks m;
  m.t_s = t_s;
  m.cost_threshold = cfg.interactive_space.cost_threshold;
  if (const auto b = daemon.base_health().read()) m.robot_odom = b->value.odom;
  if (const auto g = daemon.goal().read(); g && g->value.status == core::GoalStatus::kOk) {
    m.has_goal = true;
    m.goal_odom = g->value.goal_odom;
    m.has_person = true;
    m.person_odom = g->value.person_odom;
  }
  const auto track = daemon.human_track().read();
  if (m.has_goal && track && track->value.valid) {
    // Where the controller expects the person and q^d over its horizon (as run_controller).
    std::vector<core::Pose2> person(static_cast<size_t>(cfg.mppi.horizon_steps) + 1);
    std::vector<core::Pose2> goal(person.size());
    core::predict_person_and_goal_paths(track->value, now, cfg.mppi.step_s,
                                        firmware::human_ekf_config(cfg),
                                        m.person_odom.inverse() * m.goal_odom, person, goal);
    const auto every = static_cast<size_t>(std::max(1L, std::lround(1.0 / cfg.mppi.step_s)));
    for (size_t k = 0; k < person.size(); k += every) {
      m.predicted_person.push_back(person[k]);
      m.predicted_goal.push_back(goal[k]);
    }
  }
  if (const auto c = daemon.control_status().read(); c && c->value.tracking) {
    m.tracking = true;
    m.plan_tracking = c->value.best_cost.tracking;
    m.plan_collision = c->value.best_cost.collision;
    m.plan_barrier = c->value.best_cost.barrier;
  }
  const std::string base = fmt::format("{}-t{:.1f}", stem, t_s);
  const std::string image = std::filesystem::path(base + ".pgm").filename().string();
  m.age_image = std::filesystem::path(base + "-age.pgm").filename().string();
  m.obstacle_settled_s = cfg.obstacle_speed.settled_s;
  std::ofstream(base + ".pgm", std::ios::binary) << costmap_pgm(*map);
  std::ofstream(base + "-age.pgm", std::ios::binary) << costmap_age_pgm(*map);
  std::ofstream(base + ".yaml") << costmap_yaml(*map, image, m);
}
}  // namespace

SimRunResult run_simulation(const SimRunOptions& o) {
  using Clock = std::chrono::steady_clock;
  const auto wall_start = Clock::now();
  SimRunResult result;
  // Quiet: warnings and above (a caller that asked for less, e.g. companion-eval running trials
  // in parallel, keeps its level; the level is global, so it is only ever raised here).
  const auto level = spdlog::get_level();
  const bool raise = o.quiet && level < spdlog::level::warn;
  if (raise) spdlog::set_level(spdlog::level::warn);

  hal::SimClock clock;
  hal::SystemdNotifier notifier;  // no NOTIFY_SOCKET in a simulation: a no-op
  SimWorldConfig world_cfg = world_config(o.config, o.seed);
  world_cfg.person_avoids_robot = o.person_avoids_robot;
  world_cfg.replayed_avoid_robot = o.replayed_avoid_robot;
  world_cfg.person_sway_rad = o.person_sway_rad;
  SimWorld world(o.scenario, world_cfg, clock);
  firmware::DaemonConfig cfg = o.config;
  cfg.mppi.seed = o.seed;
  firmware::Daemon daemon(cfg, notifier);
  // The learned selector when policy.file names one, as companiond attaches it (a file that does
  // not load is the caller's error: companion-eval checks it before any trial).
  if (!cfg.policy.file.empty()) {
    core::PolicyLoadResult policy = firmware::load_configured_policy(cfg);
    if (!policy.policy) throw std::runtime_error("policy.file: " + policy.error);
    daemon.attach_policy(std::move(*policy.policy));
  }
  daemon.attach_base(world.take_base_bus());
  daemon.attach_tracker(world.take_tracker_link());
  daemon.attach_lidar(world.take_lidar_source());
  std::unique_ptr<hal::VirtualCanBus> sniffer = world.open_can_sniffer();

  MetricsConfig metrics_cfg;
  metrics_cfg.ellipse_a_m = cfg.interactive_space.ellipse_a_m;
  metrics_cfg.ellipse_b_m = cfg.interactive_space.ellipse_b_m;
  metrics_cfg.sample_period_s = o.sample_period_s;
  RunMetricsRecorder recorder(metrics_cfg);
  auto tasks = daemon.bindings();
  for (auto& t : tasks) {
    // Wall time of the planning tasks (the simulated clock does not advance inside a task).
    std::vector<double>* into = t.spec.name == "policy"    ? &result.policy_ms
                                : t.spec.name == "control" ? &result.control_ms
                                                           : nullptr;
    if (into == nullptr) continue;
    // Planning time counts the runs that planned: a holding control task or a policy without a
    // person does next to nothing, and would only dilute the quantiles.
    const bool is_control = t.spec.name == "control";
    t.fn = [into, is_control, &daemon, fn = t.fn](const core::Tick& tick) {
      const auto t0 = Clock::now();
      fn(tick);
      const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
      bool planned = false;
      if (is_control) {
        const auto c = daemon.control_status().read();
        planned = c && c->value.tracking;
      } else {
        const auto g = daemon.goal().read();
        planned = g && g->value.status == core::GoalStatus::kOk;
      }
      if (planned) into->push_back(ms);
    };
  }
  const double step_s = world.config().step_s;
  std::vector<double> costmap_at = o.costmap_at_s;
  std::sort(costmap_at.begin(), costmap_at.end());
  size_t next_costmap = 0;
  const auto step_ns = static_cast<uint32_t>(std::lround(1.0 / step_s));
  tasks.push_back({core::TaskSpec{"world", step_ns, 1000, firmware::kGroupRealtime, 255},
                   [&](const core::Tick& tick) {
                     const double t_s = core::to_seconds(tick.now);
                     if (o.script) o.script(t_s, world, daemon);
                     while (next_costmap < costmap_at.size() && t_s >= costmap_at[next_costmap]) {
                       write_costmap_snapshot(daemon, cfg, tick.now, o.costmap_stem);
                       ++next_costmap;
                     }
                     world.step(tick.now);
                     const core::Pose2 robot = world.robot_pose();
                     recorder.record(t_s, step_s, robot, world.person_pose(),
                                     world.pedestrian_positions(),
                                     world.footprint_clearance_static(),
                                     world.footprint_clearance_people(), daemon_view(daemon));
                     while (auto f = sniffer->receive()) {
                       if (o.capture_can) result.can_out.push_back(f->frame);
                     }
                   }});
  firmware::Executor executor(clock, firmware::group_table(), std::move(tasks));
  daemon.attach(executor);
  daemon.mark_initialized();
  const double duration = o.duration_s > 0 ? o.duration_s : o.scenario.duration_s;
  const core::Nanos end(static_cast<int64_t>(duration * 1e9));
  clock.set_horizon(end);
  std::thread stopper([&] {
    clock.wait_until_idle_at(end);
    executor.stop();
  });
  executor.run(core::Nanos(0));
  stopper.join();

  result.metrics = recorder.finish();
  result.samples = recorder.samples();
  if (const auto c = daemon.control_status().read()) {
    const firmware::ControlStatus& v = c->value;
    result.controller = ControllerCounts{v.runs,
                                         v.failures,
                                         v.repairs,
                                         v.closing_limits,
                                         v.guided_plans,
                                         v.paths_planned,
                                         v.path_guided_plans,
                                         v.orbits_planned,
                                         v.orbit_guided_plans,
                                         v.obstacle_limits};
  }
  result.final_status = daemon.status_line();
  result.wall_s = std::chrono::duration<double>(Clock::now() - wall_start).count();
  if (raise) spdlog::set_level(level);
  return result;
}

}  // namespace sim
