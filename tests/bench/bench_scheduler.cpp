// Real-clock benchmark of the fixed-rate scheduler: runs companiond's task table (same rates,
// groups and priorities) with synthetic CPU work per task, including a long 10 Hz lidar run,
// and prints per-task period jitter, start latency, run time, overruns and skips. Runs the
// threaded rate groups and, as the baseline in the same invocation, the single-thread mode.
//
//   build/release/tests/bench/bench_scheduler --duration-s 20 --lidar-work-ms 60
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <map>

#include "firmware/scheduler/executor.hpp"
#include "firmware/task_table.hpp"
#include "hal/linux_clock.hpp"
#include "hal/realtime.hpp"

namespace {

using core::Nanos;

void spin_for(Nanos d) {
  const Nanos end = hal::monotonic_now() + d;
  while (hal::monotonic_now() < end) {
  }
}

std::vector<firmware::TaskBinding> synthetic_table(const std::map<std::string_view, Nanos>& work) {
  std::vector<firmware::TaskBinding> out;
  for (const auto& row : firmware::task_table()) {
    const auto it = work.find(row.spec.name);
    const Nanos w = it != work.end() ? it->second : Nanos(0);
    out.push_back({row.spec, [w](const core::Tick&) { spin_for(w); }});
  }
  return out;
}

void print_stats(const firmware::Executor& ex, double seconds) {
  std::printf("  %-10s %5s %8s | %-24s | %-16s | %-16s | %5s %5s\n", "task", "Hz", "runs",
              "period jitter p50/p99/max", "start late p99/max", "run p50/p99 (us)", "over",
              "skip");
  for (size_t i = 0; i < ex.task_count(); ++i) {
    const auto& s = ex.stats(i);
    std::printf(
        "  %-10s %5u %8llu | %6.0f / %6.0f / %6.0f us | %6.0f / %6.0f us | %6.0f / %6.0f | %5llu "
        "%5llu\n",
        std::string(ex.spec(i).name).c_str(), ex.spec(i).rate_hz,
        static_cast<unsigned long long>(s.runs()), core::to_us(s.period_jitter().quantile(0.5)),
        core::to_us(s.period_jitter().quantile(0.99)), core::to_us(s.period_jitter().max()),
        core::to_us(s.start_latency().quantile(0.99)), core::to_us(s.start_latency().max()),
        core::to_us(s.run_time().quantile(0.5)), core::to_us(s.run_time().quantile(0.99)),
        static_cast<unsigned long long>(s.overruns()),
        static_cast<unsigned long long>(s.skipped()));
  }
  (void)seconds;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"scheduler jitter benchmark on the real clock"};
  double duration_s = 10.0;
  double lidar_work_ms = 60.0;
  double control_work_ms = 1.0;
  bool realtime = true;
  std::string mode = "both";
  app.add_option("--duration-s", duration_s, "seconds per mode");
  app.add_option("--lidar-work-ms", lidar_work_ms, "CPU time of each 10 Hz lidar run");
  app.add_option("--control-work-ms", control_work_ms, "CPU time of each 100 Hz control run");
  app.add_option("--mode", mode, "threaded, single or both")
      ->check(CLI::IsMember({"threaded", "single", "both"}));
  app.add_option("--realtime", realtime, "SCHED_FIFO rate-group threads (threaded mode)");
  CLI11_PARSE(app, argc, argv);

  const std::map<std::string_view, Nanos> work{
      {"tracker", std::chrono::microseconds(50)},
      {"base", std::chrono::microseconds(50)},
      {"supervisor", std::chrono::microseconds(10)},
      {"control", std::chrono::microseconds(static_cast<int64_t>(control_work_ms * 1000))},
      {"policy", std::chrono::microseconds(200)},
      {"lidar", std::chrono::microseconds(static_cast<int64_t>(lidar_work_ms * 1000))},
  };
  std::printf(
      "work per run: tracker 50 us, base 50 us, supervisor 10 us, control %.1f ms, "
      "policy 200 us, lidar %.1f ms; %.0f s per mode\n",
      control_work_ms, lidar_work_ms, duration_s);
  const Nanos duration =
      std::chrono::duration_cast<Nanos>(std::chrono::duration<double>(duration_s));

  if (mode == "threaded" || mode == "both") {
    hal::LinuxClock clock;
    firmware::Executor ex(clock, firmware::group_table(), synthetic_table(work));
    ex.start(clock.now() + std::chrono::milliseconds(20), realtime);
    std::string rt = realtime ? "SCHED_FIFO" : "SCHED_OTHER";
    for (const auto& o : ex.rt_outcomes()) {
      if (!o.ok) rt = "SCHED_OTHER (" + o.message + ")";
    }
    hal::LinuxClock().sleep_until(clock.now() + duration);
    ex.stop();
    std::printf("\nthreaded rate groups, %s:\n", rt.c_str());
    print_stats(ex, duration_s);
  }
  if (mode == "single" || mode == "both") {
    hal::LinuxClock clock;
    firmware::Executor ex(clock, firmware::group_table(), synthetic_table(work));
    std::thread stopper([&] {
      hal::LinuxClock().sleep_until(clock.now() + duration);
      ex.stop();
    });
    ex.run(clock.now() + std::chrono::milliseconds(20));
    stopper.join();
    std::printf("\nsingle thread (baseline: every task on one thread, SCHED_OTHER):\n");
    print_stats(ex, duration_s);
  }
  return 0;
}
