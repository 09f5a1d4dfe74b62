#include "core/perception/deskew.hpp"

#include <cmath>
#include <optional>

namespace core {

DeskewResult deskew(std::span<const TimedPoint> in, const PoseHistory& odom,
                    const Point3& sensor_origin, std::span<Ray> out, Nanos pose_step) {
  DeskewResult r;
  std::optional<Pose2> pose;
  Nanos pose_time{0};
  double c = 1, s = 0;
  Point3 origin;
  for (const TimedPoint& p : in) {
    if (r.rays >= out.size()) break;
    if (!pose || p.stamp - pose_time >= pose_step || pose_time - p.stamp >= pose_step) {
      pose = odom.at(p.stamp);
      pose_time = p.stamp;
      if (pose) {
        c = std::cos(pose->theta_rad);
        s = std::sin(pose->theta_rad);
        origin = Point3{pose->x_m + c * sensor_origin.x - s * sensor_origin.y,
                        pose->y_m + s * sensor_origin.x + c * sensor_origin.y, sensor_origin.z};
      }
    }
    if (!pose) {
      ++r.no_pose;
      continue;
    }
    out[r.rays++] = Ray{
        origin, Point3{pose->x_m + c * p.x - s * p.y, pose->y_m + s * p.x + c * p.y, p.z}, p.hit};
  }
  return r;
}

}  // namespace core
