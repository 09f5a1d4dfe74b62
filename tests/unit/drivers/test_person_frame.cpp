// Tracker extrinsics: sensor-in-source -> person-in-base_link, heading from the body axis.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

#include "amfitrack/person_frame.hpp"

namespace am = amfitrack;
using std::numbers::pi;

namespace {

Eigen::Matrix3d rpy(double r, double p, double y) {
  return (Eigen::AngleAxisd(y, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(p, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(r, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

am::SensorMeasurement measurement(const Eigen::Vector3d& p,
                                  const Eigen::Matrix3d& r_source_sensor) {
  am::SensorMeasurement m;
  m.position_m = {p.x(), p.y(), p.z()};
  const Eigen::Quaterniond q(r_source_sensor);
  m.quaternion_xyzw = {q.x(), q.y(), q.z(), q.w()};
  return m;
}

TEST(PersonFrame, IdentityExtrinsicsPassPositionAndYawThrough) {
  const am::PersonFrame f(am::TrackerExtrinsics{});
  const auto out = f.to_base(measurement({1.5, -0.5, 0.3}, rpy(0, 0, pi / 2)));
  ASSERT_TRUE(out);
  EXPECT_DOUBLE_EQ(out->x_m, 1.5);
  EXPECT_DOUBLE_EQ(out->y_m, -0.5);
  EXPECT_NEAR(out->z_m, 0.3, 1e-12);
  EXPECT_NEAR(out->distance_m, std::hypot(1.5, 0.5), 1e-12);
  ASSERT_TRUE(out->heading_valid);
  EXPECT_NEAR(out->heading_rad, pi / 2, 1e-9);
}

TEST(PersonFrame, SourceMountedBackwardsIsUndone) {
  // The vendor's source axes: X back toward the connector. Mounted at (0.1, 0, 0.4), turned by pi.
  am::TrackerExtrinsics e;
  e.source_xyz_m = {0.1, 0.0, 0.4};
  e.source_rpy_rad = {0, 0, pi};
  const am::PersonFrame f(e);
  const auto out = f.to_base(measurement({-1.0, 0.5, 0.2}, Eigen::Matrix3d::Identity()));
  ASSERT_TRUE(out);
  EXPECT_NEAR(out->x_m, 1.1, 1e-12);   // 1 m in front of the source, which is 0.1 m ahead
  EXPECT_NEAR(out->y_m, -0.5, 1e-12);  // the source's +y is the robot's right
  EXPECT_NEAR(out->z_m, 0.6, 1e-12);
  EXPECT_NEAR(std::abs(out->heading_rad), pi, 1e-9) << "sensor x = source x = robot's back";
}

TEST(PersonFrame, HeadingComesFromTheBodyAxisWhateverTheSensorMounting) {
  // Sensor clipped on the chest with its z axis pointing forward, x down.
  am::TrackerExtrinsics e;
  e.sensor_in_body_rpy_rad = {0, pi / 2, 0};
  const am::PersonFrame f(e);
  const Eigen::Matrix3d r_body_sensor = rpy(0, pi / 2, 0);
  for (double heading : {0.0, 0.7, -2.5, pi}) {
    for (double lean : {0.0, 0.17}) {  // leaning forward 10 degrees does not change the heading
      const Eigen::Matrix3d r_source_body = rpy(0, lean, heading);
      const auto out = f.to_base(measurement({1, 0, 0}, r_source_body * r_body_sensor));
      ASSERT_TRUE(out);
      ASSERT_TRUE(out->heading_valid);
      EXPECT_NEAR(std::remainder(out->heading_rad - heading, 2 * pi), 0.0, 1e-9)
          << heading << " lean " << lean;
    }
  }
}

TEST(PersonFrame, VerticalBodyAxisHasNoHeading) {
  const am::PersonFrame f(am::TrackerExtrinsics{});
  const auto out = f.to_base(measurement({1, 0, 0}, rpy(0, -pi / 2, 0.3)));  // body x straight up
  ASSERT_TRUE(out);
  EXPECT_FALSE(out->heading_valid);
  EXPECT_DOUBLE_EQ(out->x_m, 1.0) << "the position is still good";
}

TEST(PersonFrame, GyroYawRateIsAboutTheRobotVertical) {
  // A tilted sensor and a turned source: the yaw rate still comes out about base_link z.
  am::TrackerExtrinsics e;
  e.source_rpy_rad = {0, 0, pi};
  const am::PersonFrame f(e);
  const Eigen::Matrix3d r_source_sensor = rpy(0, pi / 2, 0.4);
  auto m = measurement({1, 0, 0}, r_source_sensor);
  // 20 deg/s about the source's (= base's, turned about z) vertical, in sensor axes.
  const Eigen::Vector3d w_sensor = r_source_sensor.transpose() * Eigen::Vector3d(0, 0, 20.0);
  m.gyro_dps = {w_sensor.x(), w_sensor.y(), w_sensor.z()};
  const auto out = f.to_base(m);
  ASSERT_TRUE(out);
  EXPECT_NEAR(out->yaw_rate_radps, 20.0 * pi / 180.0, 1e-9);
}

TEST(PersonFrame, RejectsNonRotations) {
  const am::PersonFrame f(am::TrackerExtrinsics{});
  am::SensorMeasurement m;
  m.quaternion_xyzw = {0, 0, 0, 0};
  EXPECT_FALSE(f.to_base(m));
  m.quaternion_xyzw = {0, 0, 0, std::nan("")};
  EXPECT_FALSE(f.to_base(m));
  m.quaternion_xyzw = {0, 0, 0, 1};
  m.position_m = {std::numeric_limits<double>::infinity(), 0, 0};
  EXPECT_FALSE(f.to_base(m));
  // A slightly off-norm quaternion (the wire has 1e-6 resolution) is normalised, not refused.
  m.position_m = {1, 0, 0};
  m.quaternion_xyzw = {0, 0, 0, 0.98};
  EXPECT_TRUE(f.to_base(m));
}

}  // namespace
