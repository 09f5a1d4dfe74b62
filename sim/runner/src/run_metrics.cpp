#include "sim/run_metrics.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "firmware/daemon.hpp"

namespace sim {

const char* to_string(FailureKind k) {
  switch (k) {
    case FailureKind::kNone:
      return "-";
    case FailureKind::kHitObstacle:
      return "hit obstacle";
    case FailureKind::kHitPedestrian:
      return "hit pedestrian";
    case FailureKind::kHitPerson:
      return "hit person";
    case FailureKind::kLost:
      return "lost";
  }
  return "?";
}

namespace {
constexpr double kJerkStepS = 0.02;
}  // namespace

int sector_of(double angle_rad) {
  const double turns = core::wrap_angle(angle_rad) / (2 * std::numbers::pi);
  return static_cast<int>(std::lround(turns * 8.0 + 8.0)) % 8;
}

const char* sector_name(int sector) {
  return firmware::side_name(sector);
}

void RunMetricsRecorder::record(double t_s, double dt_s, const core::Pose2& robot,
                                const core::Pose2& person,
                                const std::vector<core::Point2>& pedestrians,
                                double static_clearance_m, double people_clearance_m,
                                const DaemonView& view) {
  m_.duration_s = t_s;
  const double d = std::hypot(robot.x_m - person.x_m, robot.y_m - person.y_m);
  // Collisions: the first one fails the run.
  m_.min_static_clearance_m = std::min(m_.min_static_clearance_m, static_clearance_m);
  m_.min_people_clearance_m = std::min(m_.min_people_clearance_m, people_clearance_m);
  if (!m_.collision && (static_clearance_m <= 0 || people_clearance_m <= 0)) {
    m_.collision = true;
    m_.collision_t_s = t_s;
    if (m_.success) {
      m_.success = false;
      // Which person: the nearer centre (the clearances do not say).
      double nearest_pedestrian_m = std::numeric_limits<double>::infinity();
      for (const core::Point2& p : pedestrians) {
        nearest_pedestrian_m =
            std::min(nearest_pedestrian_m, std::hypot(robot.x_m - p.x_m, robot.y_m - p.y_m));
      }
      m_.failure_kind = static_clearance_m <= 0     ? FailureKind::kHitObstacle
                        : d <= nearest_pedestrian_m ? FailureKind::kHitPerson
                                                    : FailureKind::kHitPedestrian;
      const char* what = m_.failure_kind == FailureKind::kHitObstacle ? "an obstacle"
                         : m_.failure_kind == FailureKind::kHitPerson ? "the person"
                                                                      : "a pedestrian";
      m_.failure = fmt::format("collision with {} at t={:.1f} s", what, t_s);
    }
  }
  // Lost: > 2 m from the person for > 5 s.
  if (d > config_.far_m) {
    if (far_since_s_ < 0) far_since_s_ = t_s;
    const double far_for = t_s - far_since_s_;
    m_.longest_far_s = std::max(m_.longest_far_s, far_for);
    if (far_for > config_.far_max_s && m_.success) {
      m_.success = false;
      m_.failure_kind = FailureKind::kLost;
      m_.failure = fmt::format("more than {:.0f} m from the person for {:.0f} s at t={:.1f} s",
                               config_.far_m, config_.far_max_s, t_s);
    }
  } else {
    far_since_s_ = -1;
  }
  if (d < config_.intimate_m) m_.uncomfortable_s += dt_s;
  const core::Pose2 rel = person.inverse() * robot;  // robot in the person's frame
  const double h = rel.x_m * rel.x_m / (config_.ellipse_a_m * config_.ellipse_a_m) +
                   rel.y_m * rel.y_m / (config_.ellipse_b_m * config_.ellipse_b_m) - 1.0;
  if (h < 0) m_.inside_ellipse_s += dt_s;
  m_.min_person_distance_m = std::min(m_.min_person_distance_m, d);

  if (view.active) {
    m_.active_s += dt_s;
    m_.max_person_distance_m = std::max(m_.max_person_distance_m, d);
    dist_sum_ += d * dt_s;
    dist_time_ += dt_s;
    m_.side_time_s[static_cast<size_t>(sector_of(std::atan2(rel.y_m, rel.x_m)))] += dt_s;
    if (view.has_goal) {
      const core::Pose2 e = robot.inverse() * (person * view.goal_in_person);
      ex2_ += e.x_m * e.x_m * dt_s;
      ey2_ += e.y_m * e.y_m * dt_s;
      eth2_ += e.theta_rad * e.theta_rad * dt_s;
      m_.tracking_s += dt_s;
    }
    // Jerk of the commanded velocity, by finite differences every 20 ms (two control periods:
    // the command changes every 10 ms, the world steps every 5 ms).
    if (t_s >= jerk_next_s_) {
      const double ax = (view.cmd_vx - last_vx_) / kJerkStepS;
      const double ay = (view.cmd_vy - last_vy_) / kJerkStepS;
      if (jerk_steps_ >= 2) {
        const double jx = (ax - last_ax_) / kJerkStepS;
        const double jy = (ay - last_ay_) / kJerkStepS;
        jerk2_ += (jx * jx + jy * jy) * kJerkStepS;
        jerk_time_ += kJerkStepS;
      }
      last_ax_ = ax;
      last_ay_ = ay;
      last_vx_ = view.cmd_vx;
      last_vy_ = view.cmd_vy;
      ++jerk_steps_;
      jerk_next_s_ = t_s + kJerkStepS - 1e-9;
    }
  } else {
    jerk_steps_ = 0;
  }
  if (was_active_ && !view.active) ++m_.stops;
  was_active_ = view.active;

  if (t_s >= next_sample_s_) {
    RunSample s;
    s.t_s = t_s;
    s.robot = robot;
    s.person = person;
    s.pedestrians = pedestrians;
    s.has_goal = view.has_goal;
    const core::Pose2 goal = person * view.goal_in_person;
    s.goal = {goal.x_m, goal.y_m};
    s.active = view.active;
    s.side = view.side;
    s.cmd_vx_mps = view.cmd_vx;
    s.cmd_vy_mps = view.cmd_vy;
    s.cmd_wz_radps = view.cmd_wz;
    const double none = std::nan("");
    s.person_est_theta_rad = view.has_person_estimate ? view.person_est_theta : none;
    s.person_est_yaw_rate_radps = view.has_person_estimate ? view.person_est_yaw_rate : none;
    s.plan_tracking = view.tracking ? view.plan_tracking : none;
    s.plan_collision = view.tracking ? view.plan_collision : none;
    s.plan_barrier = view.tracking ? view.plan_barrier : none;
    samples_.push_back(std::move(s));
    next_sample_s_ = t_s + config_.sample_period_s - 1e-9;  // a step's rounding: not a skip
  }
}

RunMetrics RunMetricsRecorder::finish() const {
  RunMetrics m = m_;
  if (m.tracking_s > 0) {
    m.rmse_ex_m = std::sqrt(ex2_ / m.tracking_s);
    m.rmse_ey_m = std::sqrt(ey2_ / m.tracking_s);
    m.rmse_etheta_rad = std::sqrt(eth2_ / m.tracking_s);
  }
  if (dist_time_ > 0) m.mean_person_distance_m = dist_sum_ / dist_time_;
  if (jerk_time_ > 0) m.rms_jerk = std::sqrt(jerk2_ / jerk_time_);
  if (m.max_person_distance_m == 0) m.max_person_distance_m = m.min_person_distance_m;
  return m;
}

}  // namespace sim
