#include "sim/trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>

namespace sim {

size_t Trajectory::step_at(double t_s) const {
  const auto it = std::upper_bound(samples_.begin(), samples_.end(), t_s,
                                   [](double t, const TimedPose& s) { return t < s.t_s; });
  return static_cast<size_t>(it - samples_.begin()) - 1;
}

core::Pose2 Trajectory::pose_at(double t_s) const {
  if (samples_.empty()) return {};
  if (t_s <= samples_.front().t_s) return samples_.front().pose;
  if (t_s >= samples_.back().t_s) return samples_.back().pose;
  const size_t i = step_at(t_s);
  const TimedPose& a = samples_[i];
  const TimedPose& b = samples_[i + 1];
  const double span = b.t_s - a.t_s;
  const double s = span > 0 ? (t_s - a.t_s) / span : 1.0;
  core::Pose2 p = core::interpolate(a.pose, b.pose, s);
  p.theta_rad = s < 1.0 ? a.pose.theta_rad : b.pose.theta_rad;  // turns are sudden
  return p;
}

core::Point2 Trajectory::velocity_at(double t_s) const {
  if (samples_.size() < 2 || t_s < samples_.front().t_s || t_s >= samples_.back().t_s) return {};
  const size_t i = step_at(t_s);
  const TimedPose& a = samples_[i];
  const TimedPose& b = samples_[i + 1];
  const double span = b.t_s - a.t_s;
  if (span <= 0) return {};
  return {(b.pose.x_m - a.pose.x_m) / span, (b.pose.y_m - a.pose.y_m) / span};
}

double Trajectory::turn_rate_at(double t_s) const {
  if (samples_.size() < 2 || t_s < samples_.front().t_s || t_s >= samples_.back().t_s) return 0;
  const size_t i = step_at(t_s);
  const TimedPose& a = samples_[i];
  const TimedPose& b = samples_[i + 1];
  const double span = b.t_s - a.t_s;
  if (span <= 0) return 0;
  return core::wrap_angle(b.pose.theta_rad - a.pose.theta_rad) / span;
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

namespace {

// Observations further apart than this are not joined by a curve (a person unseen for a while):
// the gap is walked straight, and the observations either side take their velocities from their
// own side only.
constexpr double kMaxSmoothGapS = 2.0;

// The walker's velocity at each observation for a cubic Hermite curve through them: the
// derivative of the parabola through it and its two neighbours (Catmull-Rom's for uneven
// steps), so a corner is cut as walkers cut it and a straight walk at one speed stays exactly
// that. Its length is held to 3 times the slower of the two neighbouring chords' speeds
// (Fritsch and Carlson's bound, taken along the path): a person who stops (one chord of about
// 0 m/s) has about no velocity where they stop, so the curve does not carry them on past it
// and back, which would turn their heading round. The ends take their one chord.
std::vector<core::Point2> observation_velocities(const std::vector<TimedPose>& obs) {
  const size_t n = obs.size();
  std::vector<core::Point2> chord(n - 1);  // m/s
  for (size_t k = 0; k + 1 < n; ++k) {
    const double h = obs[k + 1].t_s - obs[k].t_s;
    chord[k] = {(obs[k + 1].pose.x_m - obs[k].pose.x_m) / h,
                (obs[k + 1].pose.y_m - obs[k].pose.y_m) / h};
  }
  std::vector<core::Point2> v(n);
  v.front() = chord.front();
  v.back() = chord.back();
  for (size_t k = 1; k + 1 < n; ++k) {
    const double h0 = obs[k].t_s - obs[k - 1].t_s;
    const double h1 = obs[k + 1].t_s - obs[k].t_s;
    // Beside a gap the observation is a track's end: its one chord (none between two gaps).
    if (h0 > kMaxSmoothGapS && h1 > kMaxSmoothGapS) continue;
    if (h1 > kMaxSmoothGapS) {
      v[k] = chord[k - 1];
      continue;
    }
    if (h0 > kMaxSmoothGapS) {
      v[k] = chord[k];
      continue;
    }
    const double w0 = h1 / (h0 + h1);  // the nearer neighbour's chord counts more
    const double w1 = h0 / (h0 + h1);
    core::Point2 m{w0 * chord[k - 1].x_m + w1 * chord[k].x_m,
                   w0 * chord[k - 1].y_m + w1 * chord[k].y_m};
    const double limit = 3.0 * std::min(std::hypot(chord[k - 1].x_m, chord[k - 1].y_m),
                                        std::hypot(chord[k].x_m, chord[k].y_m));
    const double len = std::hypot(m.x_m, m.y_m);
    if (len > limit) m = {m.x_m * limit / len, m.y_m * limit / len};
    v[k] = m;
  }
  return v;
}

// The cubic Hermite piece from (y0, slope m0) to (y1, m1) over a step of h, at s in [0, 1].
double hermite(double y0, double y1, double m0, double m1, double h, double s) {
  const double s2 = s * s;
  const double s3 = s2 * s;
  return (2 * s3 - 3 * s2 + 1) * y0 + (s3 - 2 * s2 + s) * h * m0 + (-2 * s3 + 3 * s2) * y1 +
         (s3 - s2) * h * m1;
}

}  // namespace

Trajectory smooth_track(const Trajectory& observed, double step_s) {
  if (observed.samples().size() < 2 || !(step_s > 0)) return observed;
  std::vector<TimedPose> obs;
  for (const TimedPose& o : observed.samples()) {
    if (obs.empty() || o.t_s > obs.back().t_s) obs.push_back(o);  // times must rise
  }
  if (obs.size() < 2) return observed;
  const std::vector<core::Point2> v = observation_velocities(obs);
  std::vector<TimedPose> out;
  auto emit_observation = [&](size_t k) {
    if (out.empty() || obs[k].t_s - out.back().t_s > 1e-9) {
      out.push_back({obs[k].t_s, {obs[k].pose.x_m, obs[k].pose.y_m, 0.0}});
    }
  };
  // On one time grid from the first observation; a gap longer than kMaxSmoothGapS keeps only
  // its two ends (walked straight, as linear interpolation did), so the samples stay within a
  // bounded number per observation whatever times a file gives.
  const double t0 = obs.front().t_s;
  const auto last_i = static_cast<size_t>(std::floor((obs.back().t_s - t0) / step_s + 1e-9));
  size_t i = 0;  // grid index, rising through the pieces
  for (size_t k = 0; k + 1 < obs.size(); ++k) {
    const core::Pose2& a = obs[k].pose;
    const core::Pose2& b = obs[k + 1].pose;
    const double h = obs[k + 1].t_s - obs[k].t_s;
    if (h > kMaxSmoothGapS) {
      emit_observation(k);
      emit_observation(k + 1);
      while (i <= last_i && t0 + static_cast<double>(i) * step_s < obs[k + 1].t_s)
        ++i;
      continue;
    }
    const bool last_piece = k + 2 == obs.size();
    for (; i <= last_i; ++i) {
      const double t = t0 + static_cast<double>(i) * step_s;
      if (!last_piece && t >= obs[k + 1].t_s) break;
      if (!out.empty() && t - out.back().t_s <= 1e-9) continue;  // a gap's end, emitted
      const double s = std::clamp((t - obs[k].t_s) / h, 0.0, 1.0);
      out.push_back({t,
                     {hermite(a.x_m, b.x_m, v[k].x_m, v[k + 1].x_m, h, s),
                      hermite(a.y_m, b.y_m, v[k].y_m, v[k + 1].y_m, h, s), 0.0}});
    }
  }
  emit_observation(obs.size() - 1);
  set_headings_from_motion(out);
  return Trajectory(std::move(out));
}

double path_length(const Trajectory& t) {
  double len = 0;
  const auto& s = t.samples();
  for (size_t i = 1; i < s.size(); ++i)
    len += std::hypot(s[i].pose.x_m - s[i - 1].pose.x_m, s[i].pose.y_m - s[i - 1].pose.y_m);
  return len;
}

namespace {

double distance(core::Point2 a, core::Point2 b) {
  return std::hypot(b.x_m - a.x_m, b.y_m - a.y_m);
}

// One piece of a walk: standing, a straight line or a circular arc, from t0_s to t1_s.
struct WalkPiece {
  double t0_s = 0;
  double t1_s = 0;
  core::Point2 from;
  core::Point2 to;  // lines (and standing: from == to)
  // Lines walked at a speed changing evenly from v0 to v1 (starting and stopping); otherwise
  // at a constant speed.
  bool eased = false;
  double v0_mps = 0;
  double v1_mps = 0;
  bool arc = false;
  core::Point2 centre;
  double radius_m = 0;
  double start_angle_rad = 0;
  double turn_rad = 0;  // signed: positive turns left

  [[nodiscard]] core::Point2 at(double t_s) const {
    const double span = t1_s - t0_s;
    double u = span > 0 ? std::clamp((t_s - t0_s) / span, 0.0, 1.0) : 1.0;
    if (eased && span > 0) {
      const double tau = u * span;
      const double walked = v0_mps * tau + 0.5 * (v1_mps - v0_mps) / span * tau * tau;
      u = walked / (0.5 * (v0_mps + v1_mps) * span);
    }
    if (arc) {
      const double a = start_angle_rad + u * turn_rad;
      return {centre.x_m + radius_m * std::cos(a), centre.y_m + radius_m * std::sin(a)};
    }
    return {from.x_m + u * (to.x_m - from.x_m), from.y_m + u * (to.y_m - from.y_m)};
  }
  // The walking direction; none while standing.
  [[nodiscard]] std::optional<double> heading_at(double t_s) const {
    if (arc) {
      const double span = t1_s - t0_s;
      const double u = span > 0 ? std::clamp((t_s - t0_s) / span, 0.0, 1.0) : 1.0;
      const double quarter = turn_rad > 0 ? std::numbers::pi / 2 : -std::numbers::pi / 2;
      return core::wrap_angle(start_angle_rad + u * turn_rad + quarter);
    }
    if (distance(from, to) < 1e-9) return std::nullopt;
    return std::atan2(to.y_m - from.y_m, to.x_m - from.x_m);
  }
};

// One end of a line: the speed there and how fast the walker changes to or from it (<= 0: at
// once).
struct SpeedRamp {
  double v_mps = 0;
  double accel_mps2 = 0;
};

class WalkBuilder {
 public:
  explicit WalkBuilder(core::Point2 start) : here_(start) {}
  void stand(double duration_s) {
    if (duration_s > 0) add_line(here_, duration_s);
  }
  void line_to(core::Point2 to, double speed_mps) {
    add_line(to, distance(here_, to) / std::max(speed_mps, 0.05));
  }
  // A line entered at `in.v_mps` and left at `out.v_mps`, at `speed_mps` between, each change
  // of speed made evenly at its ramp's accel_mps2 (<= 0: at once, as line_to). On a leg too
  // short for the full speed, the speed it allows; too short even to get from one end's speed
  // to the other's within the ramps, one even change over the whole leg.
  void line_to_eased(core::Point2 to, double speed_mps, SpeedRamp in, SpeedRamp out) {
    const double len = distance(here_, to);
    double v = std::max(speed_mps, 0.05);
    // Ramp length per unit of v^2 - v_end^2: 1 / 2a, 0 when the change is at once.
    const double k_in = in.accel_mps2 > 0 ? 0.5 / in.accel_mps2 : 0.0;
    const double k_out = out.accel_mps2 > 0 ? 0.5 / out.accel_mps2 : 0.0;
    auto ramp_m = [&](double k, double v_end) { return k * std::abs(v * v - v_end * v_end); };
    if (len < 1e-9 || ramp_m(k_in, in.v_mps) + ramp_m(k_out, out.v_mps) < 1e-12) {
      line_to(to, speed_mps);
      return;
    }
    if (ramp_m(k_in, in.v_mps) + ramp_m(k_out, out.v_mps) > len) {
      // Up from in.v to v and down to out.v within the leg: v^2 (k_in + k_out) = len +
      // k_in v_in^2 + k_out v_out^2.
      v = std::sqrt((len + k_in * in.v_mps * in.v_mps + k_out * out.v_mps * out.v_mps) /
                    (k_in + k_out));
      // Not even room to get from one end's speed to the other's at the ramps' rates.
      if (v < std::max(in.v_mps, out.v_mps)) {
        add_eased(to, in.v_mps, out.v_mps, 2.0 * len / std::max(in.v_mps + out.v_mps, 0.05));
        return;
      }
    }
    const double in_m = ramp_m(k_in, in.v_mps);
    const double out_m = ramp_m(k_out, out.v_mps);
    const core::Point2 dir{(to.x_m - here_.x_m) / len, (to.y_m - here_.y_m) / len};
    const core::Point2 start = here_;
    auto along = [&](double d) {
      return core::Point2{start.x_m + d * dir.x_m, start.y_m + d * dir.y_m};
    };
    if (in_m > 0) add_eased(along(in_m), in.v_mps, v, std::abs(v - in.v_mps) / in.accel_mps2);
    if (len - in_m - out_m > 1e-9) line_to(along(len - out_m), v);
    if (out_m > 0) add_eased(to, v, out.v_mps, std::abs(v - out.v_mps) / out.accel_mps2);
  }
  // The arc from here (on the incoming leg, heading `in_dir`) turning by `turn_rad`.
  void arc(core::Point2 in_dir, double turn_rad, double radius_m, double speed_mps) {
    const double side = turn_rad > 0 ? 1.0 : -1.0;
    WalkPiece p;
    p.arc = true;
    p.t0_s = t_s_;
    p.from = here_;
    p.centre = {here_.x_m - side * in_dir.y_m * radius_m, here_.y_m + side * in_dir.x_m * radius_m};
    p.radius_m = radius_m;
    p.start_angle_rad = std::atan2(here_.y_m - p.centre.y_m, here_.x_m - p.centre.x_m);
    p.turn_rad = turn_rad;
    p.t1_s = t_s_ + radius_m * std::abs(turn_rad) / std::max(speed_mps, 0.05);
    t_s_ = p.t1_s;
    here_ = p.at(t_s_);
    p.to = here_;
    pieces_.push_back(p);
  }
  [[nodiscard]] core::Point2 here() const { return here_; }
  [[nodiscard]] double end_s() const { return t_s_; }
  [[nodiscard]] const std::vector<WalkPiece>& pieces() const { return pieces_; }

 private:
  void add_eased(core::Point2 to, double v0_mps, double v1_mps, double duration_s) {
    add_line(to, duration_s);
    WalkPiece& p = pieces_.back();
    p.eased = true;
    p.v0_mps = v0_mps;
    p.v1_mps = v1_mps;
  }
  void add_line(core::Point2 to, double duration_s) {
    WalkPiece p;
    p.t0_s = t_s_;
    p.t1_s = t_s_ + duration_s;
    p.from = here_;
    p.to = to;
    pieces_.push_back(p);
    t_s_ += duration_s;
    here_ = to;
  }
  core::Point2 here_;
  double t_s_ = 0;
  std::vector<WalkPiece> pieces_;
};

}  // namespace

Trajectory walk(const std::vector<Waypoint>& waypoints, double start_s, double step_s,
                const CornerLimits& corner) {
  std::vector<TimedPose> out;
  if (waypoints.empty()) return Trajectory(out);
  const bool round_corners = corner.lateral_accel_mps2 > 0 && corner.turn_rate_radps > 0;
  WalkBuilder b(waypoints.front().p);
  b.stand(start_s);
  b.stand(waypoints.front().pause_s);
  // How the leg about to be walked starts: from standing, or from a corner walked slower than
  // its legs (at the corner's rate), or at its own speed.
  SpeedRamp entry{0.0, corner.start_stop_accel_mps2};
  for (size_t i = 1; i < waypoints.size(); ++i) {
    const Waypoint& w = waypoints[i];
    const core::Point2 a = waypoints[i - 1].p;
    const double len_in = distance(a, w.p);
    const bool last = i + 1 == waypoints.size();
    const double len_out = last ? 0.0 : distance(w.p, waypoints[i + 1].p);
    if (!round_corners || last || w.pause_s > 0 || len_in < 1e-6 || len_out < 1e-6) {
      const bool to_rest = last || w.pause_s > 0;
      const SpeedRamp exit =
          to_rest ? SpeedRamp{0.0, corner.start_stop_accel_mps2} : SpeedRamp{w.speed_mps, 0.0};
      b.line_to_eased(w.p, w.speed_mps, entry, exit);
      b.stand(w.pause_s);
      entry = exit;
      continue;
    }
    const core::Point2 in{(w.p.x_m - a.x_m) / len_in, (w.p.y_m - a.y_m) / len_in};
    const core::Point2 next = waypoints[i + 1].p;
    const core::Point2 out_dir{(next.x_m - w.p.x_m) / len_out, (next.y_m - w.p.y_m) / len_out};
    const double turn = std::atan2(in.x_m * out_dir.y_m - in.y_m * out_dir.x_m,
                                   in.x_m * out_dir.x_m + in.y_m * out_dir.y_m);
    if (std::abs(turn) < 1e-3) {
      b.line_to_eased(w.p, w.speed_mps, entry, {w.speed_mps, 0.0});
      entry = {w.speed_mps, 0.0};
      continue;
    }
    // The tightest arc at walking speed v: r = max(v^2 / a_lat, v / omega). Its tangent points
    // lie r tan(turn / 2) before and after the corner; where the legs are too short for that
    // (each corner may use at most 45 % of a leg), the arc is tighter and walked slower.
    double v = std::min(w.speed_mps, waypoints[i + 1].speed_mps);
    double r = std::max(v * v / corner.lateral_accel_mps2, v / corner.turn_rate_radps);
    const double half_tan = std::tan(std::abs(turn) / 2);
    const double max_cut_m = 0.45 * std::min(len_in, len_out);
    if (r * half_tan > max_cut_m) {
      r = max_cut_m / half_tan;
      v = std::min({v, std::sqrt(corner.lateral_accel_mps2 * r), corner.turn_rate_radps * r});
    }
    const double cut = r * half_tan;
    const core::Point2 arc_start{w.p.x_m - cut * in.x_m, w.p.y_m - cut * in.y_m};
    // Slowing into an arc walked slower than the leg (and speeding up out of it) at the
    // corner's rate: a person does not stop from walking speed in one step.
    b.line_to_eased(arc_start, w.speed_mps, entry, {v, corner.speed_change_accel_mps2});
    b.arc(in, turn, r, v);
    entry = {v, corner.speed_change_accel_mps2};
  }
  const double t = b.end_s();
  const auto& pieces = b.pieces();
  // Headings from the pieces (the tangent on arcs), kept while standing; before the first
  // step the walker already faces it.
  std::optional<double> first_heading;
  for (const WalkPiece& p : pieces) {
    first_heading = p.heading_at(p.t0_s);
    if (first_heading) break;
  }
  double heading = first_heading.value_or(0.0);
  size_t k = 0;
  const auto steps = static_cast<size_t>(std::floor(t / step_s + 1e-9));
  for (size_t i = 0; i <= steps; ++i) {
    const double s = static_cast<double>(i) * step_s;
    while (k + 1 < pieces.size() && pieces[k].t1_s <= s)
      ++k;
    const core::Point2 p = pieces.empty() ? b.here() : pieces[k].at(s);
    if (!pieces.empty()) heading = pieces[k].heading_at(s).value_or(heading);
    out.push_back({s, {p.x_m, p.y_m, heading}});
  }
  out.push_back({t, {b.here().x_m, b.here().y_m, heading}});
  return Trajectory(std::move(out));
}

}  // namespace sim
