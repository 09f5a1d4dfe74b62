#include "sim/trajectory.hpp"

#include <algorithm>
#include <cmath>

namespace sim {

core::Pose2 Trajectory::pose_at(double t_s) const {
  if (samples_.empty()) return {};
  if (t_s <= samples_.front().t_s) return samples_.front().pose;
  if (t_s >= samples_.back().t_s) return samples_.back().pose;
  const auto it = std::upper_bound(samples_.begin(), samples_.end(), t_s,
                                   [](double t, const TimedPose& s) { return t < s.t_s; });
  const TimedPose& b = *it;
  const TimedPose& a = *(it - 1);
  const double span = b.t_s - a.t_s;
  const double s = span > 0 ? (t_s - a.t_s) / span : 1.0;
  core::Pose2 p = core::interpolate(a.pose, b.pose, s);
  p.theta_rad = s < 1.0 ? a.pose.theta_rad : b.pose.theta_rad;  // turns are sudden
  return p;
}

core::Point2 Trajectory::velocity_at(double t_s) const {
  if (samples_.size() < 2 || t_s < samples_.front().t_s || t_s >= samples_.back().t_s) return {};
  const auto it = std::upper_bound(samples_.begin(), samples_.end(), t_s,
                                   [](double t, const TimedPose& s) { return t < s.t_s; });
  const TimedPose& b = *it;
  const TimedPose& a = *(it - 1);
  const double span = b.t_s - a.t_s;
  if (span <= 0) return {};
  return {(b.pose.x_m - a.pose.x_m) / span, (b.pose.y_m - a.pose.y_m) / span};
}

void set_headings_from_motion(std::vector<TimedPose>& samples) {
  // Below this speed a person is standing: recorded positions then jitter by centimetres and
  // their direction means nothing, so the heading is kept.
  constexpr double kWalkingMps = 0.2;
  double heading = 0;
  bool known = false;
  for (size_t i = 0; i + 1 < samples.size(); ++i) {
    const double dx = samples[i + 1].pose.x_m - samples[i].pose.x_m;
    const double dy = samples[i + 1].pose.y_m - samples[i].pose.y_m;
    const double dt = samples[i + 1].t_s - samples[i].t_s;
    if (dt > 0 && std::hypot(dx, dy) >= kWalkingMps * dt) {
      heading = std::atan2(dy, dx);
      if (!known) {
        for (size_t j = 0; j < i; ++j)
          samples[j].pose.theta_rad = heading;  // standing before the first step: face it
      }
      known = true;
    }
    samples[i].pose.theta_rad = heading;
  }
  if (!samples.empty()) samples.back().pose.theta_rad = heading;
}

double path_length(const Trajectory& t) {
  double len = 0;
  const auto& s = t.samples();
  for (size_t i = 1; i < s.size(); ++i)
    len += std::hypot(s[i].pose.x_m - s[i - 1].pose.x_m, s[i].pose.y_m - s[i - 1].pose.y_m);
  return len;
}

Trajectory walk(const std::vector<Waypoint>& waypoints, double start_s, double step_s) {
  std::vector<TimedPose> out;
  if (waypoints.empty()) return Trajectory(out);
  // Event list: (time, position) at every corner, then sampled.
  struct Knot {
    double t;
    core::Point2 p;
  };
  std::vector<Knot> knots{{0.0, waypoints.front().p}};
  double t = start_s;
  if (start_s > 0) knots.push_back({start_s, waypoints.front().p});
  if (waypoints.front().pause_s > 0) {
    t += waypoints.front().pause_s;
    knots.push_back({t, waypoints.front().p});
  }
  for (size_t i = 1; i < waypoints.size(); ++i) {
    const auto& a = waypoints[i - 1].p;
    const auto& b = waypoints[i];
    const double len = std::hypot(b.p.x_m - a.x_m, b.p.y_m - a.y_m);
    t += len / std::max(b.speed_mps, 0.05);
    knots.push_back({t, b.p});
    if (b.pause_s > 0) {
      t += b.pause_s;
      knots.push_back({t, b.p});
    }
  }
  size_t k = 0;
  const auto steps = static_cast<size_t>(std::floor(t / step_s + 1e-9));
  for (size_t i = 0; i <= steps; ++i) {
    const double s = static_cast<double>(i) * step_s;
    while (k + 1 < knots.size() && knots[k + 1].t < s)
      ++k;
    core::Point2 p = knots[k].p;
    if (k + 1 < knots.size()) {
      const double span = knots[k + 1].t - knots[k].t;
      const double u = span > 0 ? (s - knots[k].t) / span : 1.0;
      p = {knots[k].p.x_m + u * (knots[k + 1].p.x_m - knots[k].p.x_m),
           knots[k].p.y_m + u * (knots[k + 1].p.y_m - knots[k].p.y_m)};
    }
    out.push_back({s, {p.x_m, p.y_m, 0.0}});
  }
  out.push_back({t, {knots.back().p.x_m, knots.back().p.y_m, 0.0}});
  set_headings_from_motion(out);
  return Trajectory(std::move(out));
}

}  // namespace sim
