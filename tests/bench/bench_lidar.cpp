// The lidar path on one core: decode throughput (points/s) on the real capture, and one full
// 10 Hz cycle on a real scan (decode, extrinsic, deskew, recentre, ray-clear + mark, decay,
// projection + inflation) with the robot driving at 1 m/s through the (static) scanned room. The
// cycle reports p50 / p99 over repetitions.
#include <benchmark/benchmark.h>

#include <algorithm>
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
  for (auto _ : state) {
    // The robot drives at 1 m/s: odometry at 50 Hz over this scan.
    for (int k = 0; k < 6; ++k) {
      odom.add({x + 0.02 * k, 0.0, 0.0}, t + std::chrono::milliseconds(20 * k));
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
        // travel (1 m/s) up to this return's time. Deskewing undoes exactly that.
        const double travel = x + core::to_seconds(tq - t);
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
    state.counters["points"] = static_cast<double>(n);
    t += 100ms;
    x += 0.1;
  }
}
BENCHMARK(BM_LidarCycle)
    ->Args({0, 0})
    ->Args({8, 0})
    ->Args({8, 1})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->Repetitions(200)
    ->ComputeStatistics("p50", [](const std::vector<double>& v) { return quantile(v, 0.5); })
    ->ComputeStatistics("p99", [](const std::vector<double>& v) { return quantile(v, 0.99); })
    ->ReportAggregatesOnly(true);

}  // namespace

BENCHMARK_MAIN();
