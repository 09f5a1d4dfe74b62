#include "sim/social_force.hpp"

#include <cmath>

namespace sim {

namespace {
double norm(const Point2& p) {
  return std::hypot(p.x_m, p.y_m);
}
}  // namespace

double Crowd::fov_weight(const Point2& desired_dir, const Point2& force) const {
  // A force from behind (pointing along the walking direction, i.e. its source is behind) is
  // outside the field of view: -f is the direction to the source.
  const double fn = norm(force);
  if (fn <= 0) return 1.0;
  const double cos_angle = -(desired_dir.x_m * force.x_m + desired_dir.y_m * force.y_m) / fn;
  return cos_angle >= std::cos(params_.fov_half_rad) ? 1.0 : params_.outside_fov_weight;
}

Point2 Crowd::person_force(const Point2& self, double self_radius_m, const Point2& desired_dir,
                           const MovingBody& other) const {
  const double speed = norm(other.velocity);
  const double s = speed * params_.step_width_s;
  const Point2 e =
      speed > 1e-9 ? Point2{other.velocity.x_m / speed, other.velocity.y_m / speed} : Point2{0, 0};
  // V(r) = V0 exp(-b(r) / sigma), 2b = sqrt((|r| + |r - s e|)^2 - s^2), r = self - other; the
  // force is -grad V, taken by central differences.
  auto potential = [&](double rx, double ry) {
    const double r1 = std::hypot(rx, ry);
    const double r2 = std::hypot(rx - s * e.x_m, ry - s * e.y_m);
    const double sum = r1 + r2;
    const double b = 0.5 * std::sqrt(std::max(sum * sum - s * s, 0.0));
    return params_.v0_m2ps2 * std::exp(-b / params_.sigma_m);
  };
  // r is taken between the bodies' surfaces (as r_ij - d_ij in Helbing, Farkas & Vicsek 2000):
  // Helbing & Molnar's people are points, and with centre distances a walker leaned into a
  // standing robot until the centres were ~0.3 m apart, i.e. walked through its body.
  const double cx = self.x_m - other.position.x_m;
  const double cy = self.y_m - other.position.y_m;
  const double centres_m = std::hypot(cx, cy);
  constexpr double kMinSurfaceM = 1e-3;  // overlapping bodies push apart along the centre line
  const double surface_m = std::max(centres_m - self_radius_m - other.radius_m, kMinSurfaceM);
  const double scale = centres_m > 1e-9 ? surface_m / centres_m : 0.0;
  const double rx = centres_m > 1e-9 ? cx * scale : surface_m;
  const double ry = cy * scale;
  constexpr double kStep = 1e-4;
  const Point2 f{-(potential(rx + kStep, ry) - potential(rx - kStep, ry)) / (2 * kStep),
                 -(potential(rx, ry + kStep) - potential(rx, ry - kStep)) / (2 * kStep)};
  const double w = fov_weight(desired_dir, f);
  return {w * f.x_m, w * f.y_m};
}

Point2 Crowd::wall_force(const Point2& self, const Point2& desired_dir,
                         const StaticWorld& world) const {
  Point2 total{0, 0};
  auto add = [&](const Point2& nearest, double d_surface) {
    const double dx = self.x_m - nearest.x_m;
    const double dy = self.y_m - nearest.y_m;
    const double d = std::hypot(dx, dy);
    if (d_surface > params_.interaction_range_m || d < 1e-9) return;
    const double mag =
        params_.u0_m2ps2 / params_.wall_r_m * std::exp(-d_surface / params_.wall_r_m);
    Point2 f{mag * dx / d, mag * dy / d};
    const double w = fov_weight(desired_dir, f);
    total.x_m += w * f.x_m;
    total.y_m += w * f.y_m;
  };
  for (const Segment& s : world.segments) {
    const Point2 q = closest_on_segment(s, self);
    add(q, std::hypot(self.x_m - q.x_m, self.y_m - q.y_m));
  }
  for (const Circle& c : world.circles) {
    const double r = std::hypot(self.x_m - c.center.x_m, self.y_m - c.center.y_m);
    if (r < 1e-9) continue;
    const double k = c.radius_m / r;
    add({c.center.x_m + (self.x_m - c.center.x_m) * k,
         c.center.y_m + (self.y_m - c.center.y_m) * k},
        std::max(r - c.radius_m, 0.0));
  }
  return total;
}

void Crowd::step(double dt_s, const StaticWorld& world, std::span<const MovingBody> others) {
  // Everyone sees everyone's state at the start of the step (order-independent).
  bodies_.clear();
  for (const Pedestrian& p : people_)
    bodies_.push_back({p.position, p.velocity, p.radius_m});
  accel_.assign(people_.size(), Point2{});
  for (size_t i = 0; i < people_.size(); ++i) {
    Pedestrian& p = people_[i];
    // Past the goals already reached; at most one lap: a looping walker whose goals all lie within
    // goal_radius of where they stand would otherwise spin here for ever.
    for (size_t checked = 0; !p.arrived() && checked < p.goals.size(); ++checked) {
      const Point2& g = p.goals[p.next_goal];
      if (std::hypot(g.x_m - p.position.x_m, g.y_m - p.position.y_m) > params_.goal_radius_m) break;
      ++p.next_goal;
      if (p.arrived() && p.loop) p.next_goal = 0;
    }
    Point2 dir{0, 0};
    double speed = 0;
    if (!p.arrived()) {
      const Point2& g = p.goals[p.next_goal];
      const double dx = g.x_m - p.position.x_m;
      const double dy = g.y_m - p.position.y_m;
      const double d = std::hypot(dx, dy);
      if (d > 1e-9) {
        dir = {dx / d, dy / d};
        speed = p.desired_speed_mps;
      }
    }
    Point2 a{(speed * dir.x_m - p.velocity.x_m) / params_.tau_s,
             (speed * dir.y_m - p.velocity.y_m) / params_.tau_s};
    auto near = [&](const Point2& q) {
      return std::hypot(q.x_m - p.position.x_m, q.y_m - p.position.y_m) <
             params_.interaction_range_m;
    };
    for (size_t j = 0; j < bodies_.size(); ++j) {
      if (j == i || !near(bodies_[j].position)) continue;
      const Point2 f = person_force(p.position, p.radius_m, dir, bodies_[j]);
      a.x_m += f.x_m;
      a.y_m += f.y_m;
    }
    for (const MovingBody& o : others) {
      if (!near(o.position)) continue;
      const Point2 f = person_force(p.position, p.radius_m, dir, o);
      a.x_m += f.x_m;
      a.y_m += f.y_m;
    }
    const Point2 fw = wall_force(p.position, dir, world);
    accel_[i] = {a.x_m + fw.x_m, a.y_m + fw.y_m};
  }
  for (size_t i = 0; i < people_.size(); ++i) {
    Pedestrian& p = people_[i];
    p.velocity.x_m += accel_[i].x_m * dt_s;
    p.velocity.y_m += accel_[i].y_m * dt_s;
    const double v = norm(p.velocity);
    const double cap = params_.max_speed_factor * p.desired_speed_mps;
    if (v > cap) {
      p.velocity.x_m *= cap / v;
      p.velocity.y_m *= cap / v;
    }
    p.position.x_m += p.velocity.x_m * dt_s;
    p.position.y_m += p.velocity.y_m * dt_s;
  }
}

}  // namespace sim
