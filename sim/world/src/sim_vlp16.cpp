#include "sim/sim_vlp16.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace sim {

SimVlp16::SimVlp16(const SimVlp16Config& config)
    : config_(config), lasers_(vlp16::laser_table(config.product)), rng_(config.seed) {}

void SimVlp16::fire(const core::Pose2& robot, double azimuth_rad, const StaticWorld& world,
                    std::span<const Cylinder> people, uint16_t* out_distance) {
  // The sensor's azimuth turns clockwise seen from above (decoder: x = r cos az, y = -r sin az).
  const core::Pose2 sensor =
      robot * core::Pose2{config_.mount_x_m, config_.mount_y_m, config_.mount_yaw_rad};
  const double heading = sensor.theta_rad - azimuth_rad;
  const double dx = std::cos(heading);
  const double dy = std::sin(heading);
  const Point2 origin{sensor.x_m, sensor.y_m};
  hits_.clear();
  if (const auto d = world.ray(origin, dx, dy, config_.max_range_m)) {
    hits_.push_back({*d, world.height_m});
  }
  for (const Cylinder& c : people) {
    if (const auto d = ray_circle(origin, dx, dy, c.center, c.radius_m)) {
      if (*d < config_.max_range_m) hits_.push_back({*d, c.height_m});
    }
  }
  std::sort(hits_.begin(), hits_.end(), [](const Hit& a, const Hit& b) { return a.d < b.d; });
  for (size_t laser = 0; laser < vlp16::kLasers; ++laser) {
    const double el = lasers_.elevation_rad[laser];
    const double z0 = config_.mount_z_m + lasers_.vertical_offset_m[laser];
    const double slope = std::tan(el);
    // The ground: where the beam comes down to z = 0 (only for beams pointing down).
    double planar = el < 0 ? z0 / -slope : std::numeric_limits<double>::infinity();
    for (const Hit& h : hits_) {
      if (h.d >= planar) break;
      const double z = z0 + h.d * slope;
      if (z >= 0 && z <= h.height) {
        planar = h.d;
        break;
      }
    }
    uint16_t raw = 0;
    if (std::isfinite(planar)) {
      const double range = planar / std::cos(el) + config_.range_noise_m * noise_(rng_);
      if (range > 0 && range < config_.max_range_m) {
        raw = static_cast<uint16_t>(std::lround(range / vlp16::kDistanceUnitM));
      }
    }
    out_distance[laser] = raw;
  }
}

void SimVlp16::step(hal::Nanos now, const StaticWorld& world, std::span<const Cylinder> people,
                    const PoseAt& robot_at, const Sink& sink) {
  const double now_us = static_cast<double>(now.count()) / 1e3;
  if (!started_) {
    next_packet_us_ = now_us;
    started_ = true;
  }
  // 0.01 degree per microsecond of spin.
  const double az_per_us = config_.rpm / 60.0 * 36000.0 / 1e6;
  while (next_packet_us_ + kPacketUs <= now_us) {
    vlp16::RawDataPacket p;
    p.product = config_.product;
    p.mode = vlp16::ReturnMode::kStrongest;
    p.timestamp_us = static_cast<uint32_t>(std::fmod(next_packet_us_, 3.6e9));
    for (size_t b = 0; b < vlp16::kBlocks; ++b) {
      for (size_t seq = 0; seq < 2; ++seq) {
        const double t_us = next_packet_us_ + vlp16::kBlockUs * static_cast<double>(b) +
                            vlp16::kSequenceUs * static_cast<double>(seq);
        const double az = std::fmod(t_us * az_per_us, 36000.0);
        if (seq == 0) p.blocks[b].azimuth = static_cast<uint16_t>(az) % 36000;
        const core::Pose2 robot =
            robot_at(hal::Nanos(static_cast<int64_t>(std::llround(t_us * 1e3))));
        fire(robot, az / 18000.0 * std::numbers::pi, world, people,
             &p.blocks[b].distance[seq * vlp16::kLasers]);
        for (size_t k = 0; k < vlp16::kLasers; ++k)
          p.blocks[b].intensity[seq * vlp16::kLasers + k] = 60;
      }
    }
    const auto bytes = vlp16::encode_data_packet(p);
    next_packet_us_ += kPacketUs;
    sink(bytes, hal::Nanos(static_cast<int64_t>(std::llround(next_packet_us_ * 1e3))));
    ++packets_;
  }
}

}  // namespace sim
