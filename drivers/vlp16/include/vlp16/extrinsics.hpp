#pragma once
// The sensor's pose on the robot: points from the sensor frame (ROS axes) into base_link.
#include <array>

#include "vlp16/vlp16_codec.hpp"

namespace vlp16 {

struct SensorPose {
  std::array<double, 3> xyz_m{0, 0, 0};
  std::array<double, 3> rpy_rad{0, 0, 0};  // ZYX
};

class Extrinsics {
 public:
  explicit Extrinsics(const SensorPose& pose);
  // In place: x, y, z of the point become base_link coordinates.
  void apply(Point& p) const;
  [[nodiscard]] std::array<float, 3> origin() const { return {t_[0], t_[1], t_[2]}; }

 private:
  std::array<float, 9> r_{};  // row-major rotation
  std::array<float, 3> t_{};
};

}  // namespace vlp16
