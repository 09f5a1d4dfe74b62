// One full controller step as on the robot (M = 2000 samples x K = 100 steps: noise, rollouts
// with all costs, weights, update, smoothing, repair), with 1 and 2 threads; and one policy
// step's selection (W, P, G). p50 / p99 over repetitions.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <memory>
#include <random>
#include <vector>

#include "core/control/closing_speed.hpp"
#include "core/control/costmap_path.hpp"
#include "core/control/mppi.hpp"
#include "core/control/obstacle_speed.hpp"
#include "core/perception/costmap.hpp"
#include "core/perception/voxel_grid.hpp"
#include "core/planner/interactive_space.hpp"
#include "core/policy/mlp_policy.hpp"
#include "core/policy/observation.hpp"
#include "firmware/config/config_loader.hpp"
#include "firmware/daemon.hpp"

using namespace std::chrono_literals;

namespace {

double quantile(const std::vector<double>& v, double q) {
  std::vector<double> s = v;
  std::sort(s.begin(), s.end());
  return s[static_cast<size_t>(q * static_cast<double>(s.size() - 1))];
}

core::Costmap scene() {
  core::VoxelGridConfig gc;
  core::VoxelGrid g(gc);
  g.recentre(0, 0);
  std::vector<core::Ray> rays;
  for (double x = -5.5; x <= 5.5; x += 0.02) {
    rays.push_back({{0, 0, 3.0}, {x, 1.8, 0.5}});   // a corridor wall
    rays.push_back({{0, 0, 3.0}, {x, -1.8, 0.5}});  // and the other one
  }
  g.insert(rays, core::Pose2{30, 30, 0}, std::nullopt, 1s);
  core::Costmap m;
  m.build(g, core::CostmapConfig{}, 1s);
  return m;
}

// A controller step timed one at a time (100 repetitions of one iteration), reported as p50 and
// p99 in milliseconds.
void one_step_percentiles(benchmark::internal::Benchmark* b) {
  b->Unit(benchmark::kMillisecond)
      ->Iterations(1)
      ->Repetitions(100)
      ->ComputeStatistics("p50", [](const std::vector<double>& v) { return quantile(v, 0.5); })
      ->ComputeStatistics("p99", [](const std::vector<double>& v) { return quantile(v, 0.99); })
      ->ReportAggregatesOnly(true);
}

// One controller per thread count, kept across repetitions: each repetition times one warm step
// (as at 100 Hz on the robot), not the construction and the first touch of its buffers.
struct Warm {
  std::unique_ptr<core::Mppi> mppi;
  core::Costmap map;
  std::vector<core::Pose2> person;
  core::MppiInputs in;
  core::Nanos t{0};
};

// `min_ess`: the shipped configuration floors the effective sample size at 50 (a temperature
// search per step); 0 is the paper's fixed lambda = 1, the baseline in the same run.
// `guide`: 1 adds what the shipped configuration adds beyond the paper (mppi.guide_samples: one
// block of 8 structured rollouts and two steering-law integrations per step; mppi.contact_cost:
// a second tier where the Scout Mini's 0.70 x 0.60 m footprint can touch, as the daemon sets it);
// 0 is the paper's M random samples and single collision tier, the baseline in the same run.
Warm& warm(int threads, int min_ess, int guide) {
  static std::array<std::unique_ptr<Warm>, 12> cache;
  auto& w = cache[static_cast<size_t>(threads * 4 + (min_ess > 0 ? 2 : 0) + (guide > 0 ? 1 : 0))];
  if (!w) {
    w = std::make_unique<Warm>();
    core::MppiConfig cfg;  // K = 100, M = 2000
    cfg.threads = threads;
    cfg.min_effective_samples = min_ess;
    if (guide > 0) {  // exactly what the daemon ships (config/companiond.yaml)
      const core::MppiConfig shipped =
          firmware::mppi_config(*firmware::load_default_config().config);
      cfg.guide_samples = shipped.guide_samples;
      cfg.contact_cost = shipped.contact_cost;
      cfg.contact_threshold = shipped.contact_threshold;
    }
    w->mppi = std::make_unique<core::Mppi>(cfg);
    w->map = scene();
    for (int k = 0; k <= 100; ++k)
      w->person.push_back({1.0 + 0.12 * k, -0.3, 0.0});
    w->in.goal = core::Pose2{0.6, 0.4, 0.0};
    w->in.person = w->person;
    w->in.costmap = &w->map;
    for (int i = 0; i < 20; ++i) {  // warm up
      w->in.now = w->t;
      w->in.current = w->mppi->step(w->in).command;
      w->t += 10ms;
    }
  }
  return *w;
}

void BM_MppiStep(benchmark::State& state) {
  Warm& w = warm(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)),
                 static_cast<int>(state.range(2)));
  for (auto _ : state) {
    w.in.now = w.t;
    const auto out = w.mppi->step(w.in);
    benchmark::DoNotOptimize(out);
    w.in.current = out.command;
    w.t += 10ms;
  }
}
BENCHMARK(BM_MppiStep)
    ->ArgNames({"threads", "min_ess", "guide"})
    ->Args({1, 0, 0})
    ->Args({1, 50, 0})
    ->Args({1, 50, 1})
    ->Args({2, 0, 0})
    ->Args({2, 50, 0})
    ->Args({2, 50, 1})
    ->Apply(one_step_percentiles);

// standoff 1: interactive_space.speed_standoff on, the person walking at 1.2 m/s (the standoff's
// bisection for each of the 64 points; 0: the paper's W, the same call).
void BM_InteractiveSpaceSelect(benchmark::State& state) {
  core::InteractiveSpaceConfig cfg;
  cfg.speed_standoff = state.range(0) != 0;
  cfg.closing.robot_decel_mps2 = 1.0;
  core::InteractiveSpace w(cfg);
  const core::Costmap map = scene();
  for (auto _ : state) {
    w.update(core::Pose2{1.2, -0.3, 0.1}, core::Pose2{0.5, 0.2, 0.3}, map, core::Point2{1.2, 0.1});
    benchmark::DoNotOptimize(core::select_by_objective(w));
  }
}
BENCHMARK(BM_InteractiveSpaceSelect)->ArgName("standoff")->Arg(0)->Arg(1);

// The closing-speed limit on the repaired command (a bisection of the stopping condition), for
// a person at a spread of places and velocities around the robot.
void BM_ClosingSpeedLimit(benchmark::State& state) {
  core::ClosingSpeedConfig c;
  c.robot_decel_mps2 = 1.0;
  const core::TwistLimits limits;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> pos(-1.5, 1.5), vel(-1.5, 1.5);
  std::vector<std::array<double, 4>> people(256);
  for (auto& p : people)
    p = {pos(rng), pos(rng), vel(rng), vel(rng)};
  size_t i = 0;
  for (auto _ : state) {
    const auto& p = people[i++ & 255U];
    benchmark::DoNotOptimize(core::limit_closing_speed({p[0], p[1]}, {p[2], p[3]},
                                                       core::Twist{1.4, 0.3, 0.5}, c, limits));
  }
}
BENCHMARK(BM_ClosingSpeedLimit);

// The controller's collision test over one step's rollout states (M = 2000 random walks of
// K = 100 steps of 5 cm from the middle of the corridor scene: 200 000 points, a third of them
// unsafe), both ways in one run: arg 0 the bilinear cost against R (what MPPI did first), 1 the
// quad-range test (what it does). Same answers (a unit test holds them equal).
void BM_CostmapCollisionTest(benchmark::State& state) {
  const core::Costmap map = scene();
  constexpr size_t kLanes = 8;
  std::vector<std::array<float, kLanes>> xs, ys;  // per block of 8 lanes and step
  std::mt19937 rng(5);
  std::normal_distribution<float> turn(0.0f, 0.05f);
  for (size_t block = 0; block < 2000 / kLanes; ++block) {
    std::array<float, kLanes> x{}, y{}, heading{};
    for (size_t j = 0; j < kLanes; ++j)
      heading[j] = std::uniform_real_distribution<float>(-3.14f, 3.14f)(rng);
    for (int k = 0; k < 100; ++k) {
      for (size_t j = 0; j < kLanes; ++j) {
        heading[j] += turn(rng);
        x[j] += 0.05f * std::cos(heading[j]);
        y[j] += 0.05f * std::sin(heading[j]);
      }
      xs.push_back(x);
      ys.push_back(y);
    }
  }
  const int how = static_cast<int>(state.range(0));
  size_t unsafe = 0;
  for (auto _ : state) {
    unsafe = 0;
    for (size_t b = 0; b < xs.size(); ++b) {
      const auto& x = xs[b];
      const auto& y = ys[b];
      for (size_t j = 0; j < kLanes; ++j) {
        const bool o =
            how == 0 ? map.cost(x[j], y[j]) >= 30.0 : map.cost_at_least(x[j], y[j], 30.0);
        unsafe += o ? 1U : 0U;
      }
    }
    benchmark::DoNotOptimize(unsafe);
  }
  state.counters["unsafe_fraction"] =
      static_cast<double>(unsafe) / static_cast<double>(xs.size() * kLanes);
}
BENCHMARK(BM_CostmapCollisionTest)->ArgName("way")->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

// A wall across the way (x = 1.5 m, y from -0.4 m to 3 m: its short end below the line from the
// robot at the origin to q^d at (3, 0)), on the daemon's 12 m costmap; with `closed` 1, the wall
// is a box round q^d too, so no way exists and the search stops at its bound.
core::Costmap wall_scene(bool closed) {
  core::VoxelGridConfig gc;
  core::VoxelGrid g(gc);
  g.recentre(0, 0);
  std::vector<core::Ray> rays;
  auto wall = [&](double x0, double y0, double x1, double y1) {
    for (double f = 0; f <= 1.0; f += 0.005)
      rays.push_back({{0, 0, 3.0}, {x0 + f * (x1 - x0), y0 + f * (y1 - y0), 0.5}});
  };
  wall(1.5, -0.4, 1.5, 3.0);
  if (closed) {
    wall(1.5, -1.5, 1.5, -0.4);
    wall(1.5, -1.5, 4.5, -1.5);
    wall(4.5, -1.5, 4.5, 3.0);
    wall(4.5, 3.0, 1.5, 3.0);
  }
  g.insert(rays, core::Pose2{30, 30, 0}, std::nullopt, 1s);
  core::Costmap m;
  // Ten seconds after the scan: walls the obstacle limit counts (obstacle_speed.settled_s).
  m.build(g, core::CostmapConfig{}, 11s);
  return m;
}

// One costmap path (mppi.path_guide's, per control step while an obstacle's core is on the line
// to q^d): coarsening the 240 x 240 map to 0.1 m cells, then A*. `closed` 0: round the wall's
// short end; 1: no way, the search ends at max_expansions (the bound on the step's work).
void BM_CostmapPath(benchmark::State& state) {
  const bool closed = state.range(0) != 0;
  const core::Costmap map = wall_scene(closed);
  core::CostmapPathPlanner planner;
  std::vector<core::Point2> path;
  const core::CostmapPathConfig config;
  core::CostmapPathResult r{};
  for (auto _ : state) {
    planner.set_map(map, 0.1);  // as the controller does, once per step
    r = planner.plan({0.0, 0.0}, {3.0, 0.0}, config, path);
    benchmark::DoNotOptimize(path.data());
  }
  state.counters["found"] = r == core::CostmapPathResult::kFound ? 1 : 0;
  state.counters["expansions"] = planner.expansions();
}
BENCHMARK(BM_CostmapPath)->ArgName("closed")->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

// The obstacle speed limit on the command (obstacle_speed.hpp), inside the closed box of
// wall_scene(true) (3 x 4.5 m), the robot 0.2-0.8 m off its west wall, for a spread of poses and
// commands up to the limits: the obstacle cells in reach gathered from the costmap, then the
// projections. `speed` scales the commands (the window grows with the stopping distance).
void BM_ObstacleSpeedLimit(benchmark::State& state) {
  const core::Costmap map = wall_scene(true);
  core::ObstacleSpeedConfig c;
  c.robot_decel_mps2 = 1.0;
  core::ObstacleSpeedLimit limit(c);
  const double speed = static_cast<double>(state.range(0)) / 100.0;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> x(2.0, 2.6), y(-1.0, 2.5), th(-3.1, 3.1);
  std::uniform_real_distribution<double> vx(-1.8, 1.8), vy(-1.5, 1.5), wz(-2.0, 2.0);
  std::vector<std::pair<core::Pose2, core::Twist>> cases(256);
  for (auto& [pose, u] : cases) {
    pose = core::Pose2{x(rng), y(rng), th(rng)};
    u = core::Twist{speed * vx(rng), speed * vy(rng), speed * wz(rng)};
  }
  size_t i = 0;
  int limited = 0;
  for (auto _ : state) {
    const auto& [pose, u] = cases[i++ & 255U];
    const auto r = limit.apply(map, pose, u);
    limited += r.limited ? 1 : 0;
    benchmark::DoNotOptimize(r);
  }
  state.counters["limited"] = benchmark::Counter(limited, benchmark::Counter::kAvgIterations);
}
BENCHMARK(BM_ObstacleSpeedLimit)
    ->ArgName("speed_pct")
    ->Arg(50)
    ->Arg(100)
    ->Unit(benchmark::kMicrosecond);

// Warms the controller up (20 steps at 100 Hz), then times one step per iteration; the counter
// `name` says whether the last timed step had `flag` set (the option under test acted).
void time_steps(benchmark::State& state, core::Mppi& mppi, core::MppiInputs& in,
                bool core::MppiOutput::*flag, const char* name) {
  core::Nanos t{0};
  for (int i = 0; i < 20; ++i) {
    in.now = t;
    in.current = mppi.step(in).command;
    t += 10ms;
  }
  bool acted = false;
  for (auto _ : state) {
    in.now = t;
    const auto out = mppi.step(in);
    benchmark::DoNotOptimize(out);
    acted = out.*flag;
    in.current = out.command;
    t += 10ms;
  }
  state.counters[name] = acted ? 1 : 0;
}

// A full controller step as shipped (guide samples, contact tier, effective-sample floor; 1
// thread) with the wall on the line to q^d: `path` 0 without the path sample (the baseline in
// the same run), 1 with it (the straight-line test, a path planned every step, a ninth
// structured rollout).
void BM_MppiStepPathGuide(benchmark::State& state) {
  core::MppiConfig cfg = firmware::mppi_config(*firmware::load_default_config().config);
  cfg.threads = 1;
  cfg.path_guide = state.range(0) != 0;
  core::Mppi mppi(cfg);
  const core::Costmap map = wall_scene(false);
  core::MppiInputs in;
  in.goal = core::Pose2{3.0, 0.0, 0.0};
  in.costmap = &map;
  time_steps(state, mppi, in, &core::MppiOutput::path_planned, "path_planned");
}
BENCHMARK(BM_MppiStepPathGuide)->ArgName("path")->Arg(0)->Arg(1)->Apply(one_step_percentiles);

// A full controller step as shipped (1 thread) with q^d across the person: a person standing at
// the origin, the robot on their right at the ellipse, q^d on their left. `orbit` 0 without the
// orbit sample (the baseline in the same run), 1 with it (the chord test and one more
// steering-law integration every step).
void BM_MppiStepOrbitGuide(benchmark::State& state) {
  core::MppiConfig cfg = firmware::mppi_config(*firmware::load_default_config().config);
  cfg.threads = 1;
  cfg.orbit_guide = state.range(0) != 0;
  core::Mppi mppi(cfg);
  const std::vector<core::Pose2> person(static_cast<size_t>(cfg.horizon_steps) + 1,
                                        core::Pose2{0.0, 0.0, 0.0});
  core::MppiInputs in;
  in.robot = core::Pose2{0.0, -0.8, 0.0};
  in.goal = core::Pose2{0.0, 0.7, 0.0};
  in.person = person;
  time_steps(state, mppi, in, &core::MppiOutput::orbit_planned, "orbit_planned");
}
BENCHMARK(BM_MppiStepOrbitGuide)->ArgName("orbit")->Arg(0)->Arg(1)->Apply(one_step_percentiles);

// The paper's policy step: W, P, G, the observation (layout 1, 716 floats) and the MLP
// 716 -> 256 -> 128 -> 64 -> 64 (ReLU), masked argmax. Random weights: the cost is the same.
void BM_PolicyStep(benchmark::State& state) {
  const core::Costmap map = scene();
  core::InteractiveSpace w(core::InteractiveSpaceConfig{});
  std::mt19937 rng(1);
  std::normal_distribution<float> n(0.0f, 0.1f);
  core::PolicyFile p;
  p.layout_id = core::kObservationLayout;
  p.points = 64;
  const auto in = static_cast<Eigen::Index>(core::observation_size(64));
  p.mean = Eigen::VectorXf::Zero(in);
  p.stddev = Eigen::VectorXf::Ones(in);
  Eigen::Index prev = in;
  for (const int out : {256, 128, 64, 64}) {
    core::DenseLayer l;
    l.weights.resize(out, prev);
    for (Eigen::Index i = 0; i < l.weights.size(); ++i)
      l.weights.data()[i] = n(rng);
    l.bias = Eigen::VectorXf::Zero(out);
    l.activation = out == 64 && prev == 64 ? core::Activation::kNone : core::Activation::kRelu;
    p.layers.push_back(l);
    prev = out;
  }
  core::MlpPolicy policy(p);
  std::vector<float> obs(core::observation_size(64));
  std::array<bool, 64> mask{};
  core::HumanState h;
  h.pose_base = core::Pose2{1.2, -0.3, 0.1};
  for (auto _ : state) {
    w.update(h.pose_base, core::Pose2{0.5, 0.2, 0.3}, map);
    const auto cs = w.candidates();
    for (size_t i = 0; i < cs.size(); ++i)
      mask[i] = cs[i].free;
    core::ObservationInputs oi;
    oi.space = &w;
    oi.costmap = &map;
    oi.robot_odom = core::Pose2{0.5, 0.2, 0.3};
    oi.human = h;
    core::build_observation(oi, obs);
    benchmark::DoNotOptimize(policy.select(obs, mask));
  }
}
BENCHMARK(BM_PolicyStep)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
