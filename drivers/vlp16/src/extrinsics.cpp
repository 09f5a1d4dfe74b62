#include "vlp16/extrinsics.hpp"

#include <Eigen/Geometry>

namespace vlp16 {

Extrinsics::Extrinsics(const SensorPose& pose) {
  const Eigen::Matrix3d r = (Eigen::AngleAxisd(pose.rpy_rad[2], Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(pose.rpy_rad[1], Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(pose.rpy_rad[0], Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  // Row-major copy (Eigen's default storage is column-major).
  Eigen::Map<Eigen::Matrix<float, 3, 3, Eigen::RowMajor>>(r_.data()) = r.cast<float>();
  for (size_t i = 0; i < 3; ++i)
    t_[i] = static_cast<float>(pose.xyz_m[i]);
}

void Extrinsics::apply(Point& p) const {
  const float x = p.x_m;
  const float y = p.y_m;
  const float z = p.z_m;
  p.x_m = r_[0] * x + r_[1] * y + r_[2] * z + t_[0];
  p.y_m = r_[3] * x + r_[4] * y + r_[5] * z + t_[1];
  p.z_m = r_[6] * x + r_[7] * y + r_[8] * z + t_[2];
}

}  // namespace vlp16
