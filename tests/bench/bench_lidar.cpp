// The lidar path on one core: decode throughput (points/s) on the real capture, and one full
// 10 Hz cycle on a real scan (decode, extrinsic, deskew, recentre, ray-clear + mark, decay,
// projection + inflation) with the robot driving at 1 m/s through the (static) scanned room. The
// cycle reports p50 / p99 over the timed cycles.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "core/perception/costmap.hpp"
#include "core/perception/deskew.hpp"
#include "core/perception/voxel_grid.hpp"
#include "hal/capture/pcap_file.hpp"
#include "vlp16/extrinsics.hpp"
#include "vlp16/vlp16_codec.hpp"

using namespace std::chrono_literals;

namespace {

std::vector<vlp16::RawDataPacket> capture() {
  std::string err;
  auto r = hal::PcapReader::open(COMPANION_TEST_DATA "/vlp16/vlp16_strongest.pcap", err);
  std::vector<vlp16::RawDataPacket> out;
  while (r) {
    auto p = r->next(2368);
    if (!p) break;
    vlp16::RawDataPacket raw;
    if (vlp16::parse_data_packet(p->payload, raw) == vlp16::DecodeError::kNone) out.push_back(raw);
  }
  return out;
}

void BM_DecodePoints(benchmark::State& state) {
  const auto packets = capture();
  std::array<vlp16::Point, vlp16::kReturnsPerPacket> pts;
  int64_t points = 0;
  for (auto _ : state) {
    for (const auto& p : packets) {
      const size_t n = vlp16::decode_points(p, {}, pts);
      benchmark::DoNotOptimize(pts.data());
      points += static_cast<int64_t>(n);
    }
  }
  state.SetItemsProcessed(points);  // items_per_second = points/s
}
BENCHMARK(BM_DecodePoints);

void BM_ParseDataPacket(benchmark::State& state) {
  const auto packets = capture();
  const auto bytes = vlp16::encode_data_packet(packets[0]);
  vlp16::RawDataPacket raw;
  for (auto _ : state) {
    benchmark::DoNotOptimize(vlp16::parse_data_packet(bytes, raw));
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_ParseDataPacket);

double quantile(const std::vector<double>& v, double q) {
  std::vector<double> s = v;
  std::sort(s.begin(), s.end());
  return s[static_cast<size_t>(q * static_cast<double>(s.size() - 1))];
}

// Args: the no-return clearing range (0: off; 8: costmap.clear_on_no_return with the default
// clear_max_range_m) and costmap.clear_seen_through (0 / 1), so one run compares them.
// Steady state, as in the daemon: one grid for all cycles, 50 cycles (5 s, the decay time) before
// the timed ones, so voxels of earlier scans are there to be cleared, seen through and decayed and
// every buffer's pages are touched. The robot drives at 1 m/s, 2 m forth and back (the scanned
// room stays in the window). Reported: p50 / p99 of the cycle over the timed iterations.
void BM_LidarCycle(benchmark::State& state) {
  const auto packets = capture();
  vlp16::DecodeOptions decode;
  decode.no_return_range_m = static_cast<float>(state.range(0));
  core::VoxelGridConfig gc;  // 12 m x 12 m at 5 cm, 0.05..2.0 m band (39 layers)
  gc.size_xy_m = 12.0;
  gc.resolution_m = 0.05;
  gc.clear_max_range_m = 8.0;
  gc.clear_seen_through = state.range(1) != 0;
  core::VoxelGrid grid(gc);
  core::Costmap costmap;
  const core::CostmapConfig cc;
  const vlp16::Extrinsics ext(vlp16::SensorPose{{0.1, 0, 0.45}, {0, 0, 0}});
  std::vector<core::TimedPoint> timed(packets.size() * vlp16::kReturnsPerPacket);
  std::vector<core::Ray> rays(timed.size());
  std::array<vlp16::Point, vlp16::kReturnsPerPacket> pts;
  core::PoseHistory odom(256, 40ms);
  core::Nanos t = 1s;
  double x = 0;
  int cycle_index = 0;
  size_t points = 0;
  auto cycle = [&] {
    const double v = (cycle_index / 20) % 2 == 0 ? 1.0 : -1.0;  // m/s, 2 s each way
    // Odometry at 50 Hz over this scan.
    for (int k = 0; k < 6; ++k) {
      odom.add({x + v * 0.02 * k, 0.0, 0.0}, t + std::chrono::milliseconds(20 * k));
    }
    size_t n = 0;
    for (size_t p = 0; p < packets.size(); ++p) {
      const size_t m = vlp16::decode_points(packets[p], decode, pts);
      const core::Nanos packet_t = t + std::chrono::microseconds(1327 * static_cast<int64_t>(p));
      for (size_t i = 0; i < m; ++i) {
        vlp16::Point q = pts[i];
        ext.apply(q);
        const core::Nanos tq =
            packet_t + std::chrono::nanoseconds(static_cast<int64_t>(q.time_offset_us * 1000.0f));
        // The room is static in odom: seen from the moving robot, it moves back by the robot's
        // travel up to this return's time. Deskewing undoes exactly that.
        const double travel = x + v * core::to_seconds(tq - t);
        timed[n++] =
            core::TimedPoint{static_cast<double>(q.x_m) - travel, q.y_m, q.z_m, tq, !q.no_return};
      }
    }
    const auto d = core::deskew(std::span(timed.data(), n), odom, core::Point3{0.1, 0, 0.45}, rays);
    grid.recentre(x, 0.0);
    grid.insert(std::span(rays.data(), d.rays), core::Pose2{x, 0, 0},
                core::PersonSweep{{x + 1.0, 0.5}, {x + 1.1, 0.5}}, t + 100ms);
    grid.decay(t + 100ms);
    costmap.build(grid, cc, t + 100ms);
    benchmark::DoNotOptimize(costmap.data().data());
    points = n;
    t += 100ms;
    x += v * 0.1;
    ++cycle_index;
  };
  for (int i = 0; i < 50; ++i)
    cycle();
  std::vector<double> ms;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    cycle();
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                     .count());
  }
  state.counters["points"] = static_cast<double>(points);
  state.counters["p50_ms"] = quantile(ms, 0.5);
  state.counters["p99_ms"] = quantile(ms, 0.99);
  state.counters["occupied"] = static_cast<double>(grid.occupied_count());
}
BENCHMARK(BM_LidarCycle)
    ->Args({0, 0})
    ->Args({8, 0})
    ->Args({8, 1})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(200);

}  // namespace

BENCHMARK_MAIN();
