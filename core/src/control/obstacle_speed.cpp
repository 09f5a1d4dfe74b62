#include "core/control/obstacle_speed.hpp"

#include <algorithm>
#include <cmath>

namespace core {
namespace {

// The obstacle cells at least `settled_s` old within `radius_m` of the robot's centre that the
// footprint grown by `grow_m` does not cover now, in base_link.
void gather(const Costmap& map, const Pose2& robot, double radius_m, double settled_s,
            const Footprint& f, double grow_m, std::vector<Point2>& out) {
  out.clear();
  const double res = map.resolution();
  const auto cell_of = [&](double v, double origin) {
    return static_cast<int>(std::floor((v - origin) / res));
  };
  const int i0 = std::max(cell_of(robot.x_m - radius_m, map.origin_x()), 0);
  const int i1 = std::min(cell_of(robot.x_m + radius_m, map.origin_x()), map.cells() - 1);
  const int j0 = std::max(cell_of(robot.y_m - radius_m, map.origin_y()), 0);
  const int j1 = std::min(cell_of(robot.y_m + radius_m, map.origin_y()), map.cells() - 1);
  const Pose2 odom_in_base = robot.inverse();
  for (int j = j0; j <= j1; ++j) {
    for (int i = i0; i <= i1; ++i) {
      if (!map.obstacle_at_least(i, j, settled_s)) continue;
      const double x = map.origin_x() + (i + 0.5) * res;
      const double y = map.origin_y() + (j + 0.5) * res;
      if (std::hypot(x - robot.x_m, y - robot.y_m) > radius_m) continue;
      const Point2 p = odom_in_base.apply({x, y});
      if (!f.covers(p, grow_m)) out.push_back(p);
    }
  }
}

}  // namespace

double max_approach_speed_mps(double travel_m, const ObstacleSpeedConfig& c) {
  const double room_m = travel_m - c.margin_m;
  if (c.robot_decel_mps2 <= 0.0 || room_m <= 0.0) return 0.0;
  const double a = c.robot_decel_mps2;
  const double t = c.reaction_time_s;
  return a * (std::sqrt(t * t + 2.0 * room_m / a) - t);
}

Pose2 pose_after(const Twist& u, double time_s) {
  const double turn = u.wz * time_s;
  if (std::abs(turn) < 1e-9) return Pose2{u.vx * time_s, u.vy * time_s, turn};
  // The body velocity turned by w tau, integrated over tau in [0, t].
  const double s = std::sin(turn);
  const double one_minus_c = 1.0 - std::cos(turn);
  return Pose2{(u.vx * s - u.vy * one_minus_c) / u.wz, (u.vx * one_minus_c + u.vy * s) / u.wz,
               turn};
}

double fastest_point_mps(const Twist& u, const Footprint& f) {
  return std::hypot(u.vx, u.vy) + std::abs(u.wz) * f.circumscribed_radius_m();
}

ObstacleSpeedResult ObstacleSpeedLimit::apply(const Costmap& costmap, const Pose2& robot,
                                              const Twist& u) {
  ObstacleSpeedResult r;
  r.u = u;
  const ObstacleSpeedConfig& c = config_;
  if (c.robot_decel_mps2 <= 0.0 || costmap.cells() == 0) return r;  // off: nothing computed
  const double speed = fastest_point_mps(u, c.footprint);
  if (speed < 1e-9) return r;
  // The fastest point's travel to a stop from u, and the margin beyond: only cells within that
  // (plus the footprint's reach) of the centre can be covered on the way.
  const double horizon_m =
      speed * c.reaction_time_s + speed * speed / (2.0 * c.robot_decel_mps2) + c.margin_m;
  // Between two poses sweep_step_m apart no footprint point moves farther than that, so a cell
  // the footprint covers at any moment between them lies within half of it of the footprint at
  // one of them: the poses are checked with the footprint grown by half a step.
  const double grow_m = 0.5 * c.sweep_step_m;
  gather(costmap, robot, c.footprint.circumscribed_radius_m() + grow_m + horizon_m + 1e-6,
         c.settled_s, c.footprint, grow_m, cells_);
  r.obstacle_cells_looked = static_cast<int>(cells_.size());
  if (cells_.empty()) return r;
  // Along the arc, every sweep_step_m of the fastest point's travel, the last pose that covers
  // no cell.
  const int steps = static_cast<int>(std::ceil(horizon_m / c.sweep_step_m));
  double free_m = horizon_m;
  bool hit = false;
  for (int i = 1; i <= steps && !hit; ++i) {
    const double travel_m = std::min(i * c.sweep_step_m, horizon_m);
    const Pose2 base_in_start = pose_after(u, travel_m / speed).inverse();
    for (const Point2& p : cells_) {
      if (c.footprint.covers(base_in_start.apply(p), grow_m)) {
        hit = true;
        free_m = (i - 1) * c.sweep_step_m;
        break;
      }
    }
  }
  r.free_travel_m = hit ? free_m : 1e9;
  if (!hit) return r;
  r.scale = std::min(1.0, max_approach_speed_mps(free_m, c) / speed);
  if (r.scale < 1.0) {
    r.u = Twist{u.vx * r.scale, u.vy * r.scale, u.wz * r.scale};
    r.limited = true;
  }
  return r;
}

}  // namespace core
