// companiond: the companion robot daemon. Loads and validates the configuration, sets up
// real-time scheduling, runs the task table until SIGTERM/SIGINT, then stops the robot before
// exiting. See README.md ("Deploy on the robot", "Diagnose").
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <optional>

#include "amfitrack/open_link.hpp"
#include "firmware/capture_recorder.hpp"
#include "firmware/config/config_loader.hpp"
#include "firmware/daemon.hpp"
#include "firmware/logging.hpp"
#include "firmware/task_table.hpp"
#include "hal/can/can_bus.hpp"
#include "hal/linux_clock.hpp"
#include "hal/net/udp_socket.hpp"
#include "hal/realtime.hpp"
#include "hal/sd_notify.hpp"
#include "openmp_wait.hpp"
#include "show_status.hpp"
#include "sim/sim_run.hpp"
#include "sim_mode.hpp"

namespace {

int print_errors(const std::vector<firmware::ConfigError>& errors) {
  for (const auto& e : errors)
    std::cerr << "config error: " << e.to_string() << "\n";
  return 2;
}

// Waits up to `timeout` for SIGINT/SIGTERM (blocked in every thread); returns the signal or 0.
int wait_signal(const sigset_t& set, std::chrono::milliseconds timeout) {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(timeout.count() / 1000);
  ts.tv_nsec = static_cast<long>((timeout.count() % 1000) * 1'000'000);
  const int sig = sigtimedwait(&set, nullptr, &ts);
  return sig > 0 ? sig : 0;
}

int run(int argc, char** argv, const companiond::OpenmpWaitPolicy& omp_wait) {
  CLI::App app{"companiond - companion robot daemon (Amfitrack + VLP-16 + Scout Mini)"};
  std::string config_path;
  std::string check_path;
  bool print = false;
  bool reference = false;
  double duration_s = 0.0;
  std::string sink_name = "auto";
  std::string status_file;
  std::string record_dir;
  std::string show_status_path;
  bool live = false;
  bool list_scenarios = false;
  companiond::SimOptions sim_opts;
  app.add_option("-c,--config", config_path, "YAML configuration (keys: config/README.md)");
  app.add_option("--check-config", check_path, "validate FILE, print the verdict and exit");
  app.add_flag("--print-config", print, "print the effective configuration and exit");
  app.add_flag("--config-reference", reference, "print the Markdown reference of every key");
  app.add_option("--duration-s", duration_s, "stop by itself after this many seconds (0: run)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--log-sink", sink_name, "auto (journald under systemd), console, journald")
      ->check(CLI::IsMember({"auto", "console", "journald"}));
  app.add_option("--status-file", status_file,
                 "write the machine-readable status (JSON) here every second, atomically");
  app.add_option("--record", record_dir,
                 "write a capture of every device's traffic here (candump, amfi0 log, pcap)");
  app.add_option("--show-status", show_status_path,
                 "print the status file a running companiond writes (--status-file) and exit");
  app.add_flag("--live", live, "print a one-line live status every second on stdout");
  auto* simg = app.add_option_group("simulation", "with devices 'sim' (config/sim.yaml)");
  simg->add_option("--scenario", sim_opts.scenario, "built-in scenario (--list-scenarios)");
  simg->add_flag("--list-scenarios", list_scenarios, "list the built-in scenarios and exit");
  simg->add_option("--seed", sim_opts.seed, "seed of the world and the controller");
  simg->add_option("--pedestrians", sim_opts.pedestrians_file,
                   "recorded pedestrians 'frame id x y' to replay (instead of --scenario)");
  simg->add_option("--frame-period", sim_opts.frame_period_s,
                   "seconds between consecutive frame values in --pedestrians")
      ->check(CLI::PositiveNumber);
  simg->add_option("--follow", sim_opts.follow_id,
                   "id of the recorded person to accompany (default: who walks farthest)");
  simg->add_flag("--sim-clock", sim_opts.sim_clock,
                 "run on the simulated clock (deterministic, faster than real time)");
  simg->add_option("--report", sim_opts.report_dir,
                   "write the run report here at the end (report.md, trajectory.svg, ...)");
  CLI11_PARSE(app, argc, argv);

  if (!show_status_path.empty()) return companiond::show_status(show_status_path);
  if (list_scenarios) {
    for (const auto& s : sim::builtin_scenarios())
      std::cout << s.name << "  " << s.description << "\n";
    return 0;
  }

  if (reference) {
    std::cout << firmware::config_reference_markdown();
    return 0;
  }
  if (!check_path.empty()) {
    const auto r = firmware::load_config_file(check_path);
    if (!r.ok()) return print_errors(r.errors);
    std::cout << check_path << ": OK\n";
    return 0;
  }
  const auto loaded = config_path.empty() ? firmware::load_default_config()
                                          : firmware::load_config_file(config_path);
  if (!loaded.ok()) return print_errors(loaded.errors);
  const firmware::DaemonConfig& cfg = *loaded.config;
  if (print) {
    std::cout << firmware::print_config(cfg);
    return 0;
  }

  const auto sink = sink_name == "console"    ? firmware::LogSink::kConsole
                    : sink_name == "journald" ? firmware::LogSink::kJournald
                                              : firmware::LogSink::kAuto;
  firmware::setup_logging(cfg.logging.level, sink);
  spdlog::info("companiond starting (config: {})",
               config_path.empty() ? std::string("built-in defaults") : config_path);
  for (const auto& row : firmware::task_table()) {
    spdlog::info("task {:<10} {:>4} Hz budget {:>5} us group {} prio {}{}", row.spec.name,
                 row.spec.rate_hz, row.spec.budget_us, firmware::group_table()[row.spec.group].name,
                 row.spec.priority,
                 row.pending.empty() ? std::string()
                                     : " - not yet implemented: " + std::string(row.pending));
  }
  if (omp_wait.value.empty() && cfg.mppi.threads > 1) {
    spdlog::warn(
        "OpenMP: MPPI on {} threads, wait policy libgomp's default (spin) ({}); its "
        "workers spin at the control group's priority (set OMP_WAIT_POLICY=passive)",
        cfg.mppi.threads, omp_wait.source);
  } else {
    spdlog::info("OpenMP: MPPI on {} threads, wait policy {} ({})", cfg.mppi.threads,
                 omp_wait.value.empty() ? "default" : omp_wait.value, omp_wait.source);
  }
  spdlog::info("devices: tracker '{}', lidar '{}', base '{}'", cfg.devices.tracker,
               cfg.devices.lidar, cfg.devices.base);

  hal::RtResult mem{true, 0, "not requested"};
  if (cfg.realtime.enable) {
    mem = hal::lock_process_memory();
    if (!mem.ok && cfg.realtime.require) {
      spdlog::critical("realtime.require is set but {}", mem.message);
      firmware::shutdown_logging();
      return 1;
    }
  }

  // SIGINT/SIGTERM are taken synchronously by this thread only (blocked in every thread).
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  // The simulated world, when a device is 'sim'.
  std::optional<sim::Scenario> scenario;
  if (companiond::uses_sim(cfg)) {
    std::string error;
    scenario = companiond::build_scenario(sim_opts, error);
    if (!scenario) {
      spdlog::critical("simulation: {}", error);
      firmware::shutdown_logging();
      return 2;
    }
    if (duration_s == 0) duration_s = scenario->duration_s;
    spdlog::info("simulation: '{}' ({}), {:.1f} s, seed {}", scenario->name, scenario->description,
                 duration_s, sim_opts.seed);
    if (sim_opts.sim_clock) {
      if (cfg.devices.tracker != "sim" || cfg.devices.lidar != "sim" || cfg.devices.base != "sim") {
        spdlog::critical("--sim-clock needs every device to be 'sim'");
        firmware::shutdown_logging();
        return 2;
      }
      const int rc = companiond::run_on_sim_clock(cfg, sim_opts, *scenario, duration_s);
      firmware::shutdown_logging();
      return rc;
    }
  }

  hal::SystemdNotifier notifier;
  hal::LinuxClock clock;
  firmware::Daemon daemon(cfg, notifier);
  if (!status_file.empty()) daemon.set_status_file(status_file);
  // --record: every device end is wrapped by a tap before the daemon gets it.
  std::unique_ptr<firmware::CaptureRecorder> recorder;
  if (!record_dir.empty()) {
    std::string error;
    recorder = firmware::CaptureRecorder::open(
        record_dir, cfg, scenario ? "simulated world: " + scenario->name : "robot", error);
    if (!recorder) {
      spdlog::critical("{}", error);
      firmware::shutdown_logging();
      return 2;
    }
    spdlog::info("recording the devices' traffic into {}", record_dir);
  }
  auto base_end = [&](std::unique_ptr<hal::CanBus> bus) {
    return recorder ? recorder->wrap_base(std::move(bus), clock) : std::move(bus);
  };
  auto tracker_end = [&](std::unique_ptr<amfitrack::PacketLink> link) {
    return recorder ? recorder->wrap_tracker(std::move(link), clock) : std::move(link);
  };
  auto lidar_end = [&](std::unique_ptr<hal::DatagramSource> source) {
    if (!recorder) return source;
    std::string error;
    auto wrapped = recorder->wrap_lidar(std::move(source), error);
    if (!error.empty()) spdlog::error("--record: lidar not recorded: {}", error);
    return wrapped;
  };
  std::unique_ptr<sim::WorldThread> world;
  if (scenario) {
    world = std::make_unique<sim::WorldThread>(
        *scenario, sim::world_config(cfg, sim_opts.seed),
        sim::MetricsConfig{cfg.interactive_space.ellipse_a_m, cfg.interactive_space.ellipse_b_m},
        clock);
  }
  // The base's CAN link. Without it the robot cannot move and the supervisor says why
  // (base feedback silent); the daemon still runs so that it can be diagnosed.
  const std::string& base_uri = cfg.devices.base;
  if (base_uri != "none" && base_uri != "sim") {
    auto opened = hal::open_can(base_uri, clock, scout_mini::feedback_ids());
    if (!opened.bus) {
      spdlog::error("base: cannot open it: {}", opened.error);  // the error names the URI
    } else if (!daemon.attach_base(base_end(std::move(opened.bus)))) {
      spdlog::critical("task table: base and control tasks must share a rate group");
      firmware::shutdown_logging();
      return 1;
    } else {
      spdlog::info("base: Scout Mini on {}", base_uri);
    }
  } else if (base_uri == "sim") {
    if (!daemon.attach_base(base_end(world->world().take_base_bus()))) {
      spdlog::critical("task table: base and control tasks must share a rate group");
      firmware::shutdown_logging();
      return 1;
    }
    spdlog::info("base: simulated Scout Mini (CAN frames on an in-process bus)");
  }
  // The tracker's link: opened (and reopened after an unplug, with back-off) by the tracker task
  // itself, so a missing tracker at boot is a HOLD with a reason, not a failed start.
  const std::string& tracker_uri = cfg.devices.tracker;
  if (tracker_uri != "none" && tracker_uri != "sim") {
    std::string error;
    const auto uri = amfitrack::parse_link_uri(tracker_uri, &error);
    if (!uri) {  // the config loader checks this too; kept for a clear message
      spdlog::critical("{}", error);
      firmware::shutdown_logging();
      return 1;
    }
    daemon.attach_tracker(tracker_end(std::make_unique<amfitrack::ReconnectingLink>(
        [u = *uri]() { return amfitrack::open_link(u); }, firmware::tracker_reconnect_config(cfg),
        amfitrack::OpenMode::kBackground)));
    spdlog::info("tracker: Amfitrack on {} (sensor TX id {})", tracker_uri,
                 cfg.tracker.sensor_tx_id);
  } else if (tracker_uri == "sim") {
    daemon.attach_tracker(tracker_end(world->world().take_tracker_link()));
    spdlog::info("tracker: simulated Amfitrack (Amfiprot packets, sensor TX id {})",
                 cfg.tracker.sensor_tx_id);
  }
  // The VLP-16's data stream. Without it the supervisor holds (lidar silent) and says so.
  const std::string& lidar_uri = cfg.devices.lidar;
  if (lidar_uri != "none" && lidar_uri != "sim") {
    hal::UdpEndpoint ep;
    std::string error;
    if (!hal::parse_udp_endpoint(lidar_uri, ep, error)) {
      spdlog::critical("devices.lidar: {}", error);
      firmware::shutdown_logging();
      return 1;
    }
    auto opened = hal::UdpReceiver::open(ep, static_cast<int>(cfg.lidar.receive_buffer_bytes));
    if (!opened.receiver) {
      spdlog::error("lidar: cannot open it: {}", opened.error);
    } else {
      if (opened.receiver->buffer_bytes() < cfg.lidar.receive_buffer_bytes) {
        spdlog::warn(
            "lidar: receive buffer {} bytes, asked for {} (raise net.core.rmem_max or "
            "grant CAP_NET_ADMIN)",
            opened.receiver->buffer_bytes(), cfg.lidar.receive_buffer_bytes);
      }
      spdlog::info("lidar: VLP-16 on {}:{}", ep.address, opened.receiver->port());
      daemon.attach_lidar(lidar_end(std::move(opened.receiver)));
    }
  } else if (lidar_uri == "sim") {
    daemon.attach_lidar(lidar_end(world->world().take_lidar_source()));
    spdlog::info("lidar: simulated VLP-16 (1206-byte packets ray cast from the world)");
  }
  // The learned selector, when configured: it must load completely, or the daemon does not start.
  if (!cfg.policy.file.empty()) {
    core::PolicyLoadResult policy = firmware::load_configured_policy(cfg);
    if (!policy.policy) {
      spdlog::critical("{}", policy.error);
      firmware::shutdown_logging();
      return 1;
    }
    spdlog::info("policy: {} ({} layers), the learned selector chooses q^d", cfg.policy.file,
                 policy.policy->layers.size());
    daemon.attach_policy(std::move(*policy.policy));
  } else {
    spdlog::info("policy: none configured; the objective argmin chooses q^d");
  }
  firmware::Executor executor(clock, firmware::group_table(), daemon.bindings());
  daemon.attach(executor);
  const core::Nanos origin = clock.now() + std::chrono::milliseconds(10);
  if (world) world->start(origin, daemon);
  executor.start(origin, cfg.realtime.enable);

  if (cfg.realtime.enable) {
    std::string failed;
    std::string why;
    for (const auto& o : executor.rt_outcomes()) {
      if (!o.ok) {
        failed += (failed.empty() ? "" : ", ") + o.group;
        why = o.message;
      }
    }
    if (!failed.empty() || !mem.ok) {
      if (cfg.realtime.require) {
        spdlog::critical(
            "realtime.require is set but real-time scheduling is not permitted "
            "(groups: {}): {}",
            failed, why);
        executor.stop();
        firmware::shutdown_logging();
        return 1;
      }
      spdlog::warn("running WITHOUT real-time guarantees, deadlines may be missed under load: {}{}",
                   failed.empty() ? "" : "SCHED_FIFO refused for " + failed + ": " + why,
                   mem.ok ? "" : (failed.empty() ? "" : "; ") + mem.message);
    } else {
      spdlog::info("real-time: memory locked, SCHED_FIFO rate-group threads");
    }
  }

  daemon.mark_initialized();
  notifier.ready_with_status("started: waiting for inputs");
  spdlog::info("running; stop with Ctrl-C or SIGTERM");

  const auto started = clock.now();
  bool stopping = false;
  core::Nanos stop_deadline{0};
  core::Nanos next_live = started + std::chrono::seconds(1);
  const bool tty = isatty(STDOUT_FILENO) == 1;
  for (;;) {
    const int sig = wait_signal(signals, std::chrono::milliseconds(50));
    const auto now = clock.now();
    if (live && now >= next_live) {
      // In place on a terminal, one line per second otherwise (a log file, a pipe).
      const std::string line = companiond::live_line(daemon, world.get());
      std::cout << (tty ? "\r\033[K" : "") << line << (tty ? "" : "\n") << std::flush;
      next_live += std::chrono::seconds(1);
    }
    const bool timed_out = duration_s > 0 && core::to_seconds(now - started) >= duration_s;
    if ((sig != 0 || timed_out) && !stopping) {
      spdlog::info("{}: stopping the robot, then exiting",
                   sig != 0 ? (sig == SIGTERM ? "SIGTERM" : "SIGINT") : "--duration-s reached");
      notifier.stopping();
      daemon.request_shutdown();
      stopping = true;
      stop_deadline = now + core::from_ms(cfg.supervisor.stop_max_time_ms) + core::from_ms(500);
    } else if (sig != 0 && stopping) {
      spdlog::warn("second signal: exiting now");
      break;
    }
    if (stopping && daemon.shutdown_complete()) {
      spdlog::info("zero velocity commanded; exiting");
      break;
    }
    if (stopping && now > stop_deadline) {
      spdlog::error("controlled stop did not complete in time; exiting anyway");
      break;
    }
  }
  if (live && tty) std::cout << "\n";
  executor.stop();
  spdlog::info("final timing: {}", daemon.timing_summary());
  if (world) {
    world->stop();
    const auto& b = world->world().base().velocity();
    spdlog::info(
        "simulation: stopped at t={:.1f} s, base velocity {:.3f} {:.3f} {:.3f}, world steps "
        "late {}",
        world->time_s(), b.vx_mps, b.vy_mps, b.wz_radps, world->overruns());
    if (!sim_opts.report_dir.empty()) {
      companiond::write_report(sim_opts.report_dir, *scenario, *world,
                               fmt::format("companiond on '{}' (real time)", scenario->name),
                               daemon.status_line() + "\n" + daemon.timing_summary());
    }
  }
  firmware::shutdown_logging();
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    // First, before any thread: may start the process again (openmp_wait.hpp says why).
    const companiond::OpenmpWaitPolicy omp_wait = companiond::choose_openmp_wait_policy(argv);
    return run(argc, argv, omp_wait);
  } catch (const std::exception& e) {
    // Nothing is expected to throw past start-up; if something does, say what and fail so that
    // systemd restarts us (the base stops by itself 500 ms after the last command).
    (void)std::fprintf(stderr, "companiond: fatal: %s\n", e.what());
    return 1;
  }
}
