// Micro-benchmarks of the per-cycle core pieces (Google Benchmark).
//   build/release-bench/tests/bench/bench_core
#include <benchmark/benchmark.h>

#include "core/channel/latest_value.hpp"
#include "core/safety/motion_gate.hpp"
#include "core/safety/supervisor.hpp"
#include "core/scheduler/task_stats.hpp"
#include "core/util/histogram.hpp"

namespace {

using namespace std::chrono_literals;

void BM_SupervisorUpdate(benchmark::State& state) {
  core::Supervisor sup(core::SupervisorConfig{});
  core::SafetyInputs in;
  in.initialized = true;
  core::Nanos now = 1s;
  for (auto _ : state) {
    now += 10ms;
    in.tracker_stamp = now;
    in.lidar_stamp = now;
    in.costmap_stamp = now;
    in.base_feedback_stamp = now;
    in.control_heartbeat = now;
    in.tracker_confidence = core::TrackerConfidence::kGood;
    benchmark::DoNotOptimize(sup.update(in, now));
  }
}
BENCHMARK(BM_SupervisorUpdate);

void BM_LatestValuePublishRead(benchmark::State& state) {
  core::LatestValue<core::BodyVelocity> ch;
  core::Nanos now = 0ns;
  for (auto _ : state) {
    now += 1ms;
    ch.publish(core::BodyVelocity{0.1, 0.2, 0.3}, now);
    benchmark::DoNotOptimize(ch.read());
  }
}
BENCHMARK(BM_LatestValuePublishRead);

void BM_TaskStatsRecord(benchmark::State& state) {
  core::TaskStats stats(10ms, 3ms);
  core::Nanos t = 0ns;
  for (auto _ : state) {
    t += 10ms;
    stats.record(core::TaskTiming{t, t, t + 20us, t + 500us, t + 10ms, 0});
  }
}
BENCHMARK(BM_TaskStatsRecord);

void BM_HistogramQuantile(benchmark::State& state) {
  core::DurationHistogram h;
  for (int i = 0; i < 100000; ++i)
    h.record(core::Nanos(i * 37 % 1000000));
  for (auto _ : state)
    benchmark::DoNotOptimize(h.quantile(0.99));
}
BENCHMARK(BM_HistogramQuantile);

void BM_MotionGate(benchmark::State& state) {
  core::MotionGate gate(core::StopLimits{});
  core::Nanos now = 0ns;
  bool allowed = true;
  int i = 0;
  for (auto _ : state) {
    now += 10ms;
    if (++i % 100 == 0) allowed = !allowed;
    benchmark::DoNotOptimize(gate.update(allowed, core::BodyVelocity{0.5, 0.1, 0.2}, now));
  }
}
BENCHMARK(BM_MotionGate);

}  // namespace

BENCHMARK_MAIN();
