// The lidar pipeline: a costmap per scan from packets, deskewed with odometry; no costmap (and so
// no fresh stamp) when the odometry does not cover the scan.
#include <gtest/gtest.h>

#include <cmath>

#include "firmware/config/config_loader.hpp"
#include "firmware/lidar_pipeline.hpp"

using namespace std::chrono_literals;
using core::Nanos;

namespace {

// 600 rpm, every beam 3 m away (a round room).
vlp16::RawDataPacket room_packet(double t_us) {
  vlp16::RawDataPacket p;
  p.timestamp_us = static_cast<uint32_t>(std::fmod(t_us, 3.6e9));
  for (size_t b = 0; b < vlp16::kBlocks; ++b) {
    const double t = t_us + vlp16::kBlockUs * static_cast<double>(b);
    p.blocks[b].azimuth = static_cast<uint16_t>(std::fmod(t * 0.36, 36000.0));
    for (size_t k = 0; k < vlp16::kChannels; ++k) {
      const double el = vlp16::laser_table(vlp16::Product::kVlp16).elevation_rad[k % 16];
      p.blocks[b].distance[k] = static_cast<uint16_t>(3.0 / std::cos(el) / 0.002);
    }
  }
  return p;
}

// 600 rpm in the open, the sensor 0.45 m up: the beams that point down see the ground, those
// that point up see nothing (distance 0), except, while `pedestrian`, someone standing 2 m ahead
// (azimuth 0 +- 5 degrees).
vlp16::RawDataPacket open_packet(double t_us, bool pedestrian) {
  vlp16::RawDataPacket p = room_packet(t_us);
  for (size_t b = 0; b < vlp16::kBlocks; ++b) {
    const uint16_t az = p.blocks[b].azimuth;
    const bool ahead = az < 500 || az > 35500;
    for (size_t k = 0; k < vlp16::kChannels; ++k) {
      const double el = vlp16::laser_table(vlp16::Product::kVlp16).elevation_rad[k % 16];
      double range_m = el < 0 ? 0.45 / std::sin(-el) : 0.0;
      if (pedestrian && ahead) range_m = 2.0 / std::cos(el);
      p.blocks[b].distance[k] = static_cast<uint16_t>(range_m / 0.002);
    }
  }
  return p;
}

// The pedestrian walks away after 0.3 s; where they stood, is the costmap free 0.3 s later?
bool pedestrian_cleared(bool clear_on_no_return) {
  auto cfg = *firmware::load_default_config().config;
  cfg.costmap.clear_on_no_return = clear_on_no_return;
  firmware::LidarPipeline pipe(cfg);
  core::PoseHistory odom(64, 40ms);
  const core::Costmap* last = nullptr;
  bool seen = false;
  for (int i = 0; i < 450; ++i) {  // 0.6 s
    const double t_us = 1327.104 * i;
    const Nanos host(static_cast<int64_t>(t_us * 1000.0) + 1'000'000);
    if (i % 15 == 0) odom.add(core::Pose2{}, host);
    const bool there = t_us < 0.3e6;
    if (const auto* m = pipe.add_packet(open_packet(t_us, there), host, odom, std::nullopt)) {
      last = m;
      if (there) seen = seen || m->at(2.0, 0.0) == core::kCostLethal;
    }
  }
  EXPECT_TRUE(seen) << "the pedestrian was in the costmap while there";
  return last != nullptr && last->at(2.0, 0.0) < cfg.interactive_space.cost_threshold;
}

TEST(LidarPipeline, BeamsWithoutAReturnClearWhereAPedestrianStoodWithNothingBehind) {
  EXPECT_TRUE(pedestrian_cleared(true));
  // Without it, the voxels the upward beams marked stay until costmap.decay_s (5 s): the trail a
  // walking pedestrian leaves in open space (the downward beams' ground returns clear only low).
  EXPECT_FALSE(pedestrian_cleared(false));
}

TEST(LidarPipeline, CostmapPerScanWithOdometryAndNoneWithout) {
  const auto cfg = *firmware::load_default_config().config;
  firmware::LidarPipeline pipe(cfg);
  core::PoseHistory odom(64, 40ms);
  int maps = 0;
  const core::Costmap* last = nullptr;
  for (int i = 0; i < 300; ++i) {  // 0.4 s
    const double t_us = 1327.104 * i;
    const Nanos host(static_cast<int64_t>(t_us * 1000.0) + 1'000'000);
    if (i % 15 == 0) odom.add(core::Pose2{}, host);  // 50 Hz, standing still
    if (const auto* m = pipe.add_packet(room_packet(t_us), host, odom, std::nullopt)) {
      ++maps;
      last = m;
    }
  }
  EXPECT_GE(maps, 3);
  ASSERT_NE(last, nullptr);
  EXPECT_EQ(last->at(3.1, 0.0), core::kCostLethal);
  EXPECT_EQ(last->at(1.0, 0.0), 0);

  // The odometry stops (base silent): scans arrive but cannot be placed, so no costmap.
  int maps_without = 0;
  for (int i = 300; i < 600; ++i) {
    const double t_us = 1327.104 * i;
    const Nanos host(static_cast<int64_t>(t_us * 1000.0) + 1'000'000);
    const bool map = pipe.add_packet(room_packet(t_us), host, odom, std::nullopt) != nullptr;
    // The scan in progress when the odometry stopped is still partly covered (40 ms hold).
    if (map && i > 400) ++maps_without;
  }
  EXPECT_EQ(maps_without, 0);
  EXPECT_GE(pipe.scans_without_pose(), 3U);
  EXPECT_GT(pipe.last_scan().no_pose, 0U);
}

}  // namespace
