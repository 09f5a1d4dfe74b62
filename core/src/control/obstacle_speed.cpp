#include "core/control/obstacle_speed.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace core {
namespace {

using Limit = ObstacleSpeedLimit::Limit;

double dot(const std::array<double, 3>& a, const Twist& u) {
  return a[0] * u.vx + a[1] * u.vy + a[2] * u.wz;
}

// The footprint's farthest point from the robot's centre (m).
double reach_m(const Footprint& f) {
  return std::hypot(std::max(-f.x_min_m, f.x_max_m), std::max(-f.y_min_m, f.y_max_m));
}

// The fastest any point of the footprint moves under `u` (m/s).
double fastest_point_mps(const Twist& u, const Footprint& f) {
  return std::hypot(u.vx, u.vy) + std::abs(u.wz) * reach_m(f);
}

// How far from the robot's centre an obstacle can bind a command whose points move at most
// `speed_mps`: beyond it the gap exceeds that speed's stopping distance.
double window_m(double speed_mps, const ObstacleSpeedConfig& c) {
  const double stop_m =
      speed_mps * c.reaction_time_s + speed_mps * speed_mps / (2.0 * c.robot_decel_mps2);
  return reach_m(c.footprint) + c.margin_m + stop_m + 1e-6;
}

// The obstacle cells within `radius_m` of the robot's centre, as limits on the command.
void gather(const Costmap& map, const Pose2& robot, double radius_m, const ObstacleSpeedConfig& c,
            std::vector<Limit>& out, ObstacleSpeedResult& r) {
  out.clear();
  r.obstacle_cells_looked = 0;
  r.nearest_gap_m = 1e9;
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
      if (!map.obstacle(i, j)) continue;
      const double x = map.origin_x() + (i + 0.5) * res;
      const double y = map.origin_y() + (j + 0.5) * res;
      if (std::hypot(x - robot.x_m, y - robot.y_m) > radius_m) continue;
      const Point2 p = odom_in_base.apply({x, y});
      const Point2 q = c.footprint.nearest(p);
      double nx = p.x_m - q.x_m;
      double ny = p.y_m - q.y_m;
      double gap_m = std::hypot(nx, ny);
      Point2 at = q;
      if (gap_m < 1e-9) {  // inside the footprint: already touching; away from the centre only
        const double d = std::hypot(p.x_m, p.y_m);
        nx = d > 1e-9 ? p.x_m : 1.0;
        ny = d > 1e-9 ? p.y_m : 0.0;
        gap_m = 0.0;
        at = p;
      }
      const double norm = std::hypot(nx, ny);
      nx /= norm;
      ny /= norm;
      ++r.obstacle_cells_looked;
      r.nearest_gap_m = std::min(r.nearest_gap_m, gap_m);
      // n . (v + w x r), w x r = (-w r_y, w r_x).
      out.push_back({{nx, ny, at.x_m * ny - at.y_m * nx}, max_approach_speed_mps(gap_m, c)});
    }
  }
}

// Within [0, u] component by component: the limit slows or stops each part of the command, never
// adds motion (nor reverses it) the plan and the person's limits did not ask for.
Twist toward_zero_of(const Twist& v, const Twist& u) {
  auto within = [](double x, double bound) {
    return bound >= 0.0 ? std::clamp(x, 0.0, bound) : std::clamp(x, bound, 0.0);
  };
  return Twist{within(v.vx, u.vx), within(v.vy, u.vy), within(v.wz, u.wz)};
}

Twist solve(const std::vector<Limit>& limits, const Twist& u) {
  // Onto each broken limit in turn, then back into [0, u] (both convex, both hold zero): a few
  // sweeps. Near a wall the limits of neighbouring cells differ little and the first sweep meets
  // nearly all of them; what it keeps is the motion the limits do not mind (along a wall).
  Twist v = u;
  for (int sweep = 0; sweep < 4; ++sweep) {
    bool broken = false;
    for (const Limit& l : limits) {
      const double over = dot(l.a, v) - l.s;
      if (over <= 0.0) continue;
      broken = true;
      const double k = over / (l.a[0] * l.a[0] + l.a[1] * l.a[1] + l.a[2] * l.a[2]);
      v = toward_zero_of(Twist{v.vx - k * l.a[0], v.vy - k * l.a[1], v.wz - k * l.a[2]}, u);
    }
    if (!broken) break;
  }
  // Then toward zero until every limit holds (each is met by the zero command).
  double scale = 1.0;
  for (const Limit& l : limits) {
    const double along = dot(l.a, v);
    if (along > l.s) scale = std::min(scale, l.s / along);
  }
  if (scale < 1.0) {
    scale *= 1.0 - 1e-12;  // the product's rounding must not leave it a hair over
    v = Twist{v.vx * scale, v.vy * scale, v.wz * scale};
  }
  return v;
}

}  // namespace

double max_approach_speed_mps(double gap_m, const ObstacleSpeedConfig& c) {
  const double room_m = gap_m - c.margin_m;
  if (c.robot_decel_mps2 <= 0.0 || room_m <= 0.0) return 0.0;
  const double a = c.robot_decel_mps2;
  const double t = c.reaction_time_s;
  return a * (std::sqrt(t * t + 2.0 * room_m / a) - t);
}

ObstacleSpeedResult ObstacleSpeedLimit::apply(const Costmap& costmap, const Pose2& robot,
                                              const Twist& u) {
  ObstacleSpeedResult r;
  r.u = u;
  if (config_.robot_decel_mps2 <= 0.0 || costmap.cells() == 0) return r;
  // Only cells the command could reach before stopping can bind it; the result moves no point
  // faster than the command does (each component only shrinks), so the command's reach is it.
  gather(costmap, robot, window_m(fastest_point_mps(u, config_.footprint), config_), config_,
         limits_, r);
  r.u = solve(limits_, u);
  r.limited = r.u.vx != u.vx || r.u.vy != u.vy || r.u.wz != u.wz;
  return r;
}

}  // namespace core
