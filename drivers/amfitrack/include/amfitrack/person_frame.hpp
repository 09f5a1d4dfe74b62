#pragma once
// From the tracker's frame to the robot's: the sensor's pose in the SOURCE frame (0x1A) becomes
// the person's position and heading in `base_link`.
//   - The source is mounted on the robot: its pose in base_link comes from config (the vendor
//     guide's source axes: X back toward the USB connector, Y right, Z up; measure yours).
//   - The sensor is worn on the body: its orientation relative to the person's body frame
//     (x forward, y left, z up) comes from config too; the person's heading is the body x axis
//     projected on the floor. When the body x axis is (nearly) vertical there is no heading.
#include <Eigen/Core>
#include <array>
#include <optional>

#include "amfitrack/amfiprot_codec.hpp"

namespace amfitrack {

struct TrackerExtrinsics {
  std::array<double, 3> source_xyz_m{0, 0, 0};            // source origin in base_link
  std::array<double, 3> source_rpy_rad{0, 0, 0};          // source orientation in base_link (ZYX)
  std::array<double, 3> sensor_in_body_rpy_rad{0, 0, 0};  // sensor orientation on the body
};

struct PersonInBase {
  double x_m = 0, y_m = 0, z_m = 0;
  double heading_rad = 0;
  bool heading_valid = false;
  double yaw_rate_radps = 0;  // about base_link z, from the sensor's gyro
  double distance_m = 0;      // planar, from the base_link origin
};

// Roll, pitch, yaw (rad) -> rotation, ZYX: R = Rz(yaw) Ry(pitch) Rx(roll) (the extrinsics'
// convention).
Eigen::Matrix3d rotation_rpy(const std::array<double, 3>& rpy_rad);

class PersonFrame {
 public:
  explicit PersonFrame(const TrackerExtrinsics& extrinsics);
  // nullopt when the measurement's quaternion is not a rotation (zero or not finite) or its
  // position is not finite.
  [[nodiscard]] std::optional<PersonInBase> to_base(const SensorMeasurement& m) const;

 private:
  Eigen::Matrix3d r_base_source_;
  Eigen::Vector3d t_base_source_;
  Eigen::Matrix3d r_sensor_body_;  // body axes in sensor coordinates
};

}  // namespace amfitrack
