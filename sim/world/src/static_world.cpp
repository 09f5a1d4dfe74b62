#include "sim/static_world.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace sim {

void StaticWorld::add_polygon(const std::vector<Point2>& vertices) {
  for (size_t i = 0; i < vertices.size(); ++i) {
    segments.push_back({vertices[i], vertices[(i + 1) % vertices.size()]});
  }
}

void StaticWorld::add_box(Point2 min, Point2 max) {
  add_polygon({min, {max.x_m, min.y_m}, max, {min.x_m, max.y_m}});
}

std::optional<double> ray_circle(Point2 origin, double dx, double dy, Point2 center,
                                 double radius) {
  const double ox = origin.x_m - center.x_m;
  const double oy = origin.y_m - center.y_m;
  const double b = ox * dx + oy * dy;
  const double c = ox * ox + oy * oy - radius * radius;
  if (c <= 0) return 0.0;  // inside
  const double disc = b * b - c;
  if (disc < 0 || b > 0) return std::nullopt;
  return -b - std::sqrt(disc);
}

Point2 closest_on_segment(const Segment& s, Point2 p) {
  const double vx = s.b.x_m - s.a.x_m;
  const double vy = s.b.y_m - s.a.y_m;
  const double len2 = vx * vx + vy * vy;
  double t = len2 > 0 ? ((p.x_m - s.a.x_m) * vx + (p.y_m - s.a.y_m) * vy) / len2 : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  return {s.a.x_m + t * vx, s.a.y_m + t * vy};
}

std::optional<double> StaticWorld::ray(Point2 origin, double dx, double dy, double max_m) const {
  double best = max_m;
  bool hit = false;
  for (const Segment& s : segments) {
    // origin + t d = a + u (b - a), t >= 0, u in [0, 1].
    const double ex = s.b.x_m - s.a.x_m;
    const double ey = s.b.y_m - s.a.y_m;
    const double den = dx * ey - dy * ex;
    if (std::abs(den) < 1e-12) continue;  // parallel
    const double wx = s.a.x_m - origin.x_m;
    const double wy = s.a.y_m - origin.y_m;
    const double t = (wx * ey - wy * ex) / den;
    const double u = (wx * dy - wy * dx) / den;
    if (t >= 0 && u >= 0 && u <= 1 && t < best) {
      best = t;
      hit = true;
    }
  }
  for (const Circle& c : circles) {
    const auto t = ray_circle(origin, dx, dy, c.center, c.radius_m);
    if (t && *t < best) {
      best = *t;
      hit = true;
    }
  }
  if (!hit) return std::nullopt;
  return best;
}

double StaticWorld::distance(Point2 p, Point2* nearest) const {
  double best = std::numeric_limits<double>::infinity();
  for (const Segment& s : segments) {
    const Point2 q = closest_on_segment(s, p);
    const double d = std::hypot(p.x_m - q.x_m, p.y_m - q.y_m);
    if (d < best) {
      best = d;
      if (nearest != nullptr) *nearest = q;
    }
  }
  for (const Circle& c : circles) {
    const double r = std::hypot(p.x_m - c.center.x_m, p.y_m - c.center.y_m);
    const double d = r - c.radius_m;
    if (d < best) {
      best = d;
      if (nearest != nullptr) {
        const double k = r > 0 ? c.radius_m / r : 0.0;
        *nearest = {c.center.x_m + (p.x_m - c.center.x_m) * k,
                    c.center.y_m + (p.y_m - c.center.y_m) * k};
      }
    }
  }
  return best;
}

}  // namespace sim
