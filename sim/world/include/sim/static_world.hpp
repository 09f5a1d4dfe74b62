#pragma once
// The simulated world's fixed geometry in the world frame (metres): walls and polygon edges as
// segments, round obstacles as circles, all taller than the robot's sensors. Answers the two
// questions the simulator asks: where does a horizontal ray first hit, and how far is the
// nearest obstacle from a point (collisions, social-force walls, metrics).
#include <optional>
#include <string>
#include <vector>

#include "core/geometry/pose2.hpp"

namespace sim {

using core::Point2;

struct Segment {
  Point2 a, b;
};

struct Circle {
  Point2 center;
  double radius_m = 0;
};

struct StaticWorld {
  std::vector<Segment> segments;
  std::vector<Circle> circles;
  double height_m = 2.5;  // every static obstacle

  void add_wall(Point2 a, Point2 b) { segments.push_back({a, b}); }
  // A closed polygon (vertices in order).
  void add_polygon(const std::vector<Point2>& vertices);
  // An axis-aligned box by its corners.
  void add_box(Point2 min, Point2 max);
  void add_circle(Point2 center, double radius_m) { circles.push_back({center, radius_m}); }

  // Distance along the unit direction (dx, dy) from `origin` to the first static surface, or
  // nullopt within max_m.
  [[nodiscard]] std::optional<double> ray(Point2 origin, double dx, double dy, double max_m) const;
  // Distance from `p` to the nearest static surface (negative inside a circle), and the point of
  // that surface; infinity when the world is empty.
  [[nodiscard]] double distance(Point2 p, Point2* nearest = nullptr) const;
};

// Ray against a circle: the entry distance along the unit direction, or nullopt.
std::optional<double> ray_circle(Point2 origin, double dx, double dy, Point2 center, double radius);
// Closest point of a segment to p.
Point2 closest_on_segment(const Segment& s, Point2 p);

}  // namespace sim
