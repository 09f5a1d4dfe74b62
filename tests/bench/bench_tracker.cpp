// The tracker path, per frame: decode (UART COBS stream or HID report -> packet -> 0x1A
// measurement), extrinsics to base_link, and the human filter's update and prediction.
// Throughput is reported as frames/s (items_per_second) and bytes/s.
#include <benchmark/benchmark.h>

#include <random>

#include "amfitrack/amfiprot_codec.hpp"
#include "amfitrack/person_frame.hpp"
#include "core/human/human_ekf.hpp"

namespace am = amfitrack;
using namespace std::chrono_literals;

namespace {

am::SensorMeasurement sample(uint32_t frame_id) {
  am::SensorMeasurement m;
  m.position_m = {-1.2, 0.3, 0.05};
  m.quaternion_xyzw = {0, 0, 0.7071068, 0.7071068};
  m.sensor_status = 0x08;
  m.pose_state_raw = 1;
  m.quality_raw = 230;
  m.temperature_c = 30;
  m.frame_id = frame_id;
  return m;
}

// One second of the sensor at 120 Hz as the UART delivers it.
std::vector<uint8_t> cobs_second() {
  std::vector<uint8_t> bytes;
  for (uint32_t i = 0; i < 120; ++i) {
    const auto f = am::cobs_encode(
        am::encode_packet(am::sensor_measurement_packet(sample(i), 2, static_cast<uint8_t>(i))));
    bytes.insert(bytes.end(), f.begin(), f.end());
    bytes.push_back(0);
  }
  return bytes;
}

void BM_DecodeCobsStream(benchmark::State& state) {
  const auto bytes = cobs_second();
  am::CobsStreamDecoder dec;
  int64_t frames = 0;
  for (auto _ : state) {
    dec.feed(bytes);
    while (auto p = dec.next()) {
      const auto pl = am::decode_payload(*p);
      benchmark::DoNotOptimize(pl);
      ++frames;
    }
  }
  state.SetItemsProcessed(frames);
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * bytes.size()));
}
BENCHMARK(BM_DecodeCobsStream);

void BM_DecodeHidReport(benchmark::State& state) {
  const auto packet = am::encode_packet(am::sensor_measurement_packet(sample(7), 2, 7));
  std::array<uint8_t, am::kHidReportSize> report{};
  report[0] = 1;
  report[1] = static_cast<uint8_t>(packet.size());
  std::copy(packet.begin(), packet.end(), report.begin() + 2);
  for (auto _ : state) {
    const auto parsed = am::parse_hid_report(report);
    const auto pl = am::decode_payload(*parsed.packet);
    benchmark::DoNotOptimize(pl);
  }
  state.SetItemsProcessed(state.iterations());
  state.SetBytesProcessed(state.iterations() * static_cast<int64_t>(report.size()));
}
BENCHMARK(BM_DecodeHidReport);

void BM_PersonFrame(benchmark::State& state) {
  am::TrackerExtrinsics e;
  e.source_rpy_rad = {0, 0, 3.14159};
  const am::PersonFrame f(e);
  const auto m = sample(1);
  for (auto _ : state)
    benchmark::DoNotOptimize(f.to_base(m));
}
BENCHMARK(BM_PersonFrame);

void BM_HumanEkfUpdate(benchmark::State& state) {
  core::HumanEkf ekf(core::HumanEkfConfig{});
  std::mt19937 rng(1);
  std::normal_distribution<double> n(0, 0.05);
  const core::Nanos frame(8'333'333);
  core::Nanos t{0};
  double x = 0;
  for (auto _ : state) {
    x += 0.01;
    t += frame;
    benchmark::DoNotOptimize(ekf.update_pose({x + n(rng), n(rng), n(rng)}, true, t));
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_HumanEkfUpdate);

void BM_HumanStateAndPath(benchmark::State& state) {
  core::HumanEkf ekf(core::HumanEkfConfig{});
  for (int i = 0; i < 240; ++i) {
    ekf.update_pose({0.01 * i, 0, 0}, true, core::Nanos(8'333'333) * i);
  }
  std::array<core::Pose2, 100> path;  // the controller's horizon: K = 100 steps of 0.1 s
  const core::HumanEkfConfig cfg;
  for (auto _ : state) {
    const auto h = core::human_state(ekf.track(), 2s, core::Pose2{0.5, 0.1, 0.2}, cfg);
    core::predict_path(ekf.track(), 2s, 0.1, 0.0, 0.0, path);  // the default: constant velocity
    benchmark::DoNotOptimize(h);
    benchmark::DoNotOptimize(path);
  }
}
BENCHMARK(BM_HumanStateAndPath);

}  // namespace

BENCHMARK_MAIN();
