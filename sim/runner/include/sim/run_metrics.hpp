#pragma once
// The evaluation's measurements of one run, exactly as reference/evaluation.md defines them:
//  - failure: a collision (the robot's footprint touches an obstacle or a person), or the robot
//    centre more than 2 m from the person continuously for more than 5 s;
//  - UT: seconds with the robot centre closer than 0.45 m to the person (Hall's intimate zone);
//    also the seconds inside the CBF ellipse (h < 0);
//  - tracking error e = q^d - q^r in the robot frame, RMSE of e_x, e_y, e_theta (wrapped), over
//    the time the supervisor lets the robot move toward a chosen point; q^r the true robot, q^d
//    the chosen point of the person's W on the true person now (so the person's estimate, the
//    odometry's age and the 30 Hz selection's age all count; the daemon's own frame hid them);
//  - minimum clearances, the side distribution of the robot around the person (8 sectors of
//    the person's frame: 0 = front, 2 = left, 4 = behind, 6 = right), command jerk.
// Fed once per world step with the truth and what the daemon decided.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/geometry/pose2.hpp"

namespace sim {

struct RunSample {  // for pictures and diagnosis: every MetricsConfig::sample_period_s
  double t_s = 0;
  core::Pose2 robot;   // world
  core::Pose2 person;  // world
  std::vector<core::Point2> pedestrians;
  bool has_goal = false;
  core::Point2 goal;  // q^d in the world (the chosen point of W on the true person)
  bool active = false;
  int side = -1;                          // sector of the chosen point (0..7), -1 none
  double cmd_vx_mps = 0, cmd_vy_mps = 0;  // the daemon's last command, base_link
  // The controller's best rollout by cost term (NaN when it is not tracking): why it left q^d.
  double plan_tracking = 0, plan_collision = 0, plan_barrier = 0;
  double cmd_wz_radps = 0;  // the daemon's last command's turn rate
  // The daemon's person filter (odom frame; NaN without a track): how late it sees a turn.
  double person_est_theta_rad = 0, person_est_yaw_rate_radps = 0;
};

// What failed a run first: the tables count these.
enum class FailureKind { kNone, kHitObstacle, kHitPedestrian, kHitPerson, kLost };
const char* to_string(
    FailureKind k);  // "-", "hit obstacle", "hit pedestrian", "hit person", "lost"

struct RunMetrics {
  double duration_s = 0;
  bool success = true;
  std::string failure;  // "" or "collision with ... at t=..", "more than 2 m from the person ..."
  FailureKind failure_kind = FailureKind::kNone;
  bool collision = false;
  double collision_t_s = -1;
  double longest_far_s = 0;  // longest stretch > 2 m from the person
  double uncomfortable_s = 0;
  double inside_ellipse_s = 0;
  double active_s = 0;  // time in ACTIVE
  double tracking_s = 0;
  double rmse_ex_m = 0, rmse_ey_m = 0, rmse_etheta_rad = 0;
  double min_static_clearance_m = 1e9;
  double min_people_clearance_m = 1e9;
  double min_person_distance_m = 1e9, max_person_distance_m = 0;
  double mean_person_distance_m = 0;
  std::array<double, 8> side_time_s{};  // robot's sector around the person, while ACTIVE
  double rms_jerk = 0;                  // of the commanded planar velocity, m/s^3
  uint64_t stops = 0;                   // ACTIVE -> not ACTIVE transitions
};

struct MetricsConfig {
  double ellipse_a_m = 1.0, ellipse_b_m = 0.7;
  double intimate_m = 0.45;
  double far_m = 2.0;
  double far_max_s = 5.0;
  double sample_period_s = 0.1;
};

// What the daemon decided at this instant (from its channels).
struct DaemonView {
  bool active = false;
  bool has_goal = false;
  // q^d in the frame of the person it was chosen around (a point of their interactive space W):
  // where it is now is that point carried with the person, whatever the daemon's odometry
  // and the age of its last selection.
  core::Pose2 goal_in_person;
  int side = -1;
  double cmd_vx = 0, cmd_vy = 0, cmd_wz = 0;
  bool has_person_estimate = false;  // the person filter's heading and turn rate (odom)
  double person_est_theta = 0, person_est_yaw_rate = 0;
  bool tracking = false;  // the controller ran on q^d: plan_* hold its best rollout's terms
  double plan_tracking = 0, plan_collision = 0, plan_barrier = 0;
};

class RunMetricsRecorder {
 public:
  explicit RunMetricsRecorder(const MetricsConfig& config = {}) : config_(config) {}

  void record(double t_s, double dt_s, const core::Pose2& robot, const core::Pose2& person,
              const std::vector<core::Point2>& pedestrians, double static_clearance_m,
              double people_clearance_m, const DaemonView& view);
  [[nodiscard]] RunMetrics finish() const;
  [[nodiscard]] const std::vector<RunSample>& samples() const { return samples_; }

 private:
  MetricsConfig config_;
  RunMetrics m_;
  double far_since_s_ = -1;
  double ex2_ = 0, ey2_ = 0, eth2_ = 0;
  double dist_sum_ = 0, dist_time_ = 0;
  double next_sample_s_ = 0;
  bool was_active_ = false;
  double last_vx_ = 0, last_vy_ = 0, last_ax_ = 0, last_ay_ = 0, jerk2_ = 0;
  double jerk_time_ = 0;
  double jerk_next_s_ = 0;
  int jerk_steps_ = 0;
  std::vector<RunSample> samples_;
};

// Sector 0..7 of an angle in the person's frame (0 = ahead, counter-clockwise).
int sector_of(double angle_rad);
const char* sector_name(int sector);

}  // namespace sim
