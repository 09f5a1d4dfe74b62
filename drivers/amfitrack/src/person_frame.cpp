#include "amfitrack/person_frame.hpp"

#include <Eigen/Geometry>
#include <cmath>

namespace amfitrack {

Eigen::Matrix3d rotation_rpy(const std::array<double, 3>& a) {
  return (Eigen::AngleAxisd(a[2], Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(a[1], Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(a[0], Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

namespace {

// Below this length of the floor projection of the body x axis (i.e. within ~8 degrees of
// vertical) the heading is undefined.
constexpr double kMinHorizontal = 0.14;

}  // namespace

PersonFrame::PersonFrame(const TrackerExtrinsics& e)
    : r_base_source_(rotation_rpy(e.source_rpy_rad)),
      t_base_source_(e.source_xyz_m[0], e.source_xyz_m[1], e.source_xyz_m[2]),
      // R_body_sensor = rpy(sensor_in_body); body axes in sensor coordinates = its transpose.
      r_sensor_body_(rotation_rpy(e.sensor_in_body_rpy_rad).transpose()) {}

std::optional<PersonInBase> PersonFrame::to_base(const SensorMeasurement& m) const {
  const auto& q = m.quaternion_xyzw;
  const Eigen::Vector3d p_source(m.position_m[0], m.position_m[1], m.position_m[2]);
  const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (!p_source.allFinite() || !std::isfinite(norm) || norm < 0.5) return std::nullopt;
  const Eigen::Quaterniond q_source_sensor(q[3] / norm, q[0] / norm, q[1] / norm, q[2] / norm);

  const Eigen::Vector3d p_base = r_base_source_ * p_source + t_base_source_;
  const Eigen::Matrix3d r_base_sensor = r_base_source_ * q_source_sensor.toRotationMatrix();
  const Eigen::Matrix3d r_base_body = r_base_sensor * r_sensor_body_;

  PersonInBase out;
  out.x_m = p_base.x();
  out.y_m = p_base.y();
  out.z_m = p_base.z();
  out.distance_m = std::hypot(out.x_m, out.y_m);
  const Eigen::Vector3d forward = r_base_body.col(0);
  const double horizontal = std::hypot(forward.x(), forward.y());
  out.heading_valid = horizontal >= kMinHorizontal;
  out.heading_rad = out.heading_valid ? std::atan2(forward.y(), forward.x()) : 0.0;
  // Gyro (deg/s, sensor axes) -> angular velocity in base_link; its z part is the yaw rate.
  const Eigen::Vector3d gyro_sensor(m.gyro_dps[0], m.gyro_dps[1], m.gyro_dps[2]);
  out.yaw_rate_radps = (r_base_sensor * gyro_sensor).z() * M_PI / 180.0;
  return out;
}

}  // namespace amfitrack
