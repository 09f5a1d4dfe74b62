#pragma once
// A simulated Velodyne VLP-16 that sends what the real one sends: 1206-byte data packets of 12
// blocks x 2 firing sequences x 16 lasers, one every 1327.104 us (754/s), the azimuth advancing
// with the spin (600 rpm: 10 scans/s), the timestamp in microseconds past the hour. Each firing
// is a ray cast from the sensor's pose AT THAT TIME against the world: static obstacles (taller
// than the sensor's reach), people as vertical cylinders, and the ground plane. Ranges carry
// white noise. The bytes go to a sink (an in-process queue or a UDP socket) with their arrival
// time; the daemon's VLP-16 decoder reads them exactly as on the robot.
#include <functional>
#include <random>
#include <span>

#include "core/geometry/pose2.hpp"
#include "hal/clock.hpp"
#include "sim/static_world.hpp"
#include "vlp16/vlp16_codec.hpp"

namespace sim {

struct Cylinder {
  Point2 center;
  double radius_m = 0.25;
  double height_m = 1.75;
};

struct SimVlp16Config {
  double rpm = 600.0;
  vlp16::Product product = vlp16::Product::kVlp16;
  double range_noise_m = 0.01;  // 1 sigma (the datasheet's +-3 cm is ~2 sigma)
  double max_range_m = 100.0;
  uint32_t seed = 1;
  // The sensor on the robot (base_link at ground level): the daemon's lidar.* extrinsics.
  double mount_x_m = 0.10, mount_y_m = 0.0, mount_z_m = 0.45, mount_yaw_rad = 0.0;
};

class SimVlp16 {
 public:
  using PoseAt = std::function<core::Pose2(hal::Nanos)>;  // the robot in the world at a time
  using Sink = std::function<void(std::span<const uint8_t>, hal::Nanos arrival)>;

  explicit SimVlp16(const SimVlp16Config& config = {});

  // Sends every packet complete by `now`. `people` are the cylinders at this step's time.
  void step(hal::Nanos now, const StaticWorld& world, std::span<const Cylinder> people,
            const PoseAt& robot_at, const Sink& sink);

  [[nodiscard]] uint64_t packets_sent() const { return packets_; }

  static constexpr double kPacketUs = vlp16::kBlockUs * vlp16::kBlocks;  // 1327.104

 private:
  // One firing sequence: 16 ranges (2 mm units, 0 = none) along the given sensor azimuth.
  void fire(const core::Pose2& robot, double azimuth_rad, const StaticWorld& world,
            std::span<const Cylinder> people, uint16_t* out_distance);

  SimVlp16Config config_;
  const vlp16::LaserTable& lasers_;
  std::mt19937 rng_;
  std::normal_distribution<double> noise_{0.0, 1.0};
  bool started_ = false;
  double next_packet_us_ = 0;  // first firing of the next packet (monotonic us)
  uint64_t packets_ = 0;
  struct Hit {
    double d;
    double height;
  };
  std::vector<Hit> hits_;  // scratch, sorted by distance
};

}  // namespace sim
