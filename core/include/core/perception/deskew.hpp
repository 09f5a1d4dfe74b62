#pragma once
// Deskewing a scan: a revolution takes 100 ms, during which the robot moves up to 18 cm and
// turns up to 11 degrees. Each return (and the sensor origin its ray starts from) is moved into
// odom with the robot's pose at the return's own time.
#include <span>

#include "core/geometry/pose_history.hpp"
#include "core/perception/voxel_grid.hpp"

namespace core {

struct TimedPoint {
  double x = 0, y = 0, z = 0;  // base_link at the return's time
  Nanos stamp{0};
  bool hit = true;  // false: the beam saw nothing up to here (clears, never marks)
};

struct DeskewResult {
  size_t rays = 0;     // written to `out`
  size_t no_pose = 0;  // returns whose time the odometry history does not cover (dropped)
};

// `sensor_origin` is the lidar's origin in base_link. Poses are looked up once per
// `pose_step` of time (0.5 ms: 5 mm at 1 m/s), not per return.
DeskewResult deskew(std::span<const TimedPoint> in, const PoseHistory& odom,
                    const Point3& sensor_origin, std::span<Ray> out,
                    Nanos pose_step = std::chrono::microseconds(500));

}  // namespace core
