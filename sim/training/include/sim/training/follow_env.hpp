#pragma once
// The PPO training environment (issue 8; the paper's section IV, "training environment"): a
// person walking one of the random benchmark's worlds (obstacles, social-force pedestrians,
// optionally obstacles beside the walk), a robot that goes to the chosen point of the
// interactive space W, and the paper's reward. One step = one policy decision (30 Hz).
//
// What it shares with the daemon, so a policy trained here runs there unchanged: the scenario
// generator, the voxel grid and costmap (fed by a 2-D ray fan from the robot at 10 Hz, person
// masked, the same clearing and decay), InteractiveSpace (W, P, G) and build_observation
// (layout 1). What it does not simulate, so that one step costs ~1 ms instead of the closed
// loop's ~400 ms per simulated second: the devices' bytes, the tracker filter (the person's
// pose and velocity come from the truth plus Gaussian noise), and MPPI. The robot is a
// kinematic omnidirectional base under the controller's steering law (q^d's velocity plus
// 2/s toward q^d, the MPPI guide sample; core/control/mppi.cpp) within the base's velocity and
// acceleration limits, repaired by the controller's DCBF QP (core/control/dcbf_repair.hpp) so it
// goes round the person's ellipse, not through it. It does not go round obstacles: the policy
// has to choose points it can reach, and the closed loop (companion-eval --method policy) is
// where it is judged.
//
// Reward (reference/evaluation.md, "PPO"): r = r^h + r^a + r^c with
//   r^h = sigma_h (d_{t-1} - d_t) when d_t > D, else r_tracking   (d: robot to person, m)
//   r^a = -sigma_a |a_t - a_{t-1}|   (index distance on the ellipse, wrapped)
//   r^c = r_collision when the nearest obstacle is closer than the safety clearance.
// An episode ends when it is over (truncated), or terminates on contact (footprint circle with
// an obstacle or a pedestrian, the person's intimate zone) or when the person is lost (> 2 m for
// > 5 s, the benchmark's failure); a contact also earns r_collision.
#include <cstdint>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "core/control/dcbf_repair.hpp"
#include "core/human/human_ekf.hpp"
#include "core/perception/costmap.hpp"
#include "core/perception/voxel_grid.hpp"
#include "core/planner/interactive_space.hpp"
#include "core/planner/standoff_velocity.hpp"
#include "firmware/config/daemon_config.hpp"
#include "sim/scenario.hpp"
#include "sim/social_force.hpp"

namespace sim::training {

struct RewardConfig {
  double sigma_h_per_m = 100.0;       // r^h weight (per metre closed)
  double tracking_reward = 50.0;      // r_tracking
  double tracking_distance_m = 0.75;  // D
  double sigma_a_per_index = 0.5;     // r^a weight (per index of W the choice moves)
  double collision_reward = -200.0;   // r_collision
  double safety_clearance_m = 0.75;   // obstacle nearer than this to the robot's centre: r^c
};

struct Rewards {
  double human = 0, action = 0, collision = 0;
  [[nodiscard]] double total() const { return human + action + collision; }
};

// The index distance between two points of W (n points on the ellipse), wrapped: 0 .. n/2.
int wrapped_index_distance(int a, int b, int n);
// The three terms for one step. `previous_action` < 0: no previous choice (r^a = 0).
Rewards step_rewards(const RewardConfig& c, double previous_distance_m, double distance_m,
                     int action, int previous_action, int points, double obstacle_clearance_m,
                     bool contact);

struct FollowEnvConfig {
  core::InteractiveSpaceConfig space;  // n, R, the objective's weights (a, b randomised below)
  RewardConfig reward;
  double policy_period_s = 1.0 / 30.0;
  double lidar_period_s = 0.1;
  double episode_s = 30.0;
  // Domain randomisation, drawn per episode.
  double speed_min_mps = 0.7, speed_max_mps = 1.5;  // the person
  double a_min_m = 0.8, a_max_m = 1.2;              // interactive-space semi-axes
  double b_min_m = 0.55, b_max_m = 0.9;
  int pedestrians_max = 12;
  int obstacles_max = 10;
  double constrained_probability = 0.4;  // obstacles beside the walk
  double beside_clearance_min_m = 0.8, beside_clearance_max_m = 1.6;
  // The dead_end case's corridor (the person turns back at its closed end) instead of a random
  // world: the one constrained case the random worlds never make, where the point behind the
  // person is past them. 0: none, and nothing drawn for it (earlier trainings' worlds unchanged).
  double dead_end_probability = 0;
  double start_distance_min_m = 0.8, start_distance_max_m = 1.6;  // robot from the person
  double position_noise_m = 0.03;  // the person's estimate (tracker filter error)
  double heading_noise_rad = 0.05;
  double velocity_noise_mps = 0.05;
  // The robot: the daemon's limits and the steering law's gain.
  double max_vx_mps = 1.8, max_vy_mps = 1.5;
  double max_yaw_rate_radps = 2.0;
  double accel_mps2 = 1.5;
  double yaw_accel_radps2 = 3.0;
  double steering_gain_per_s = 2.0;
  double barrier_delta = 0.5;  // the DCBF's delta (dcbf.delta)
  // Contacts and loss.
  double robot_radius_m = 0.46;  // circle round the 0.70 x 0.60 m footprint
  double intimate_m = 0.45;      // robot centre to the person's centre
  double far_m = 2.0, far_max_s = 5.0;
  core::VoxelGridConfig grid;
  core::CostmapConfig costmap;
  int lidar_beams = 720;
  double lidar_range_m = 10.0;
  double sensor_height_m = 0.4;
};

// The environment as the daemon's configuration has it: W (n, a, b as the centre of the
// randomised range, R, the objective's weights), the base's limits, the voxel grid and costmap.
FollowEnvConfig follow_env_config(const firmware::DaemonConfig& daemon);

struct StepResult {
  Rewards rewards;
  bool terminated = false;  // contact or lost: no value after this step
  bool truncated = false;   // the episode's time is over
  int action_taken = -1;    // the point actually used (a masked action falls back to argmin G)
};

struct EpisodeStats {
  double return_sum = 0;
  int steps = 0;
  bool contact = false;
  bool contact_person =
      false;  // the contact was the followed person (else an obstacle or a pedestrian)
  bool lost = false;
  double near_obstacle_s = 0;  // time with r^c
  int jumps = 0;  // the chosen point moving > 0.3 m round the ellipse from one step to the next
  double duration_s = 0;
};

class FollowEnv {
 public:
  FollowEnv(const FollowEnvConfig& config, uint64_t seed);

  // Starts an episode in a new random world; writes the first observation.
  void reset(std::span<float> observation, std::span<bool> mask);
  // Applies the choice of point `action` (index into W), advances one policy period, and
  // writes the next observation (after a terminal step: the first of a new episode).
  StepResult step(int action, std::span<float> observation, std::span<bool> mask);

  [[nodiscard]] size_t observation_size() const;
  [[nodiscard]] int points() const { return config_.space.points; }
  [[nodiscard]] const EpisodeStats& last_episode() const { return last_episode_; }
  [[nodiscard]] uint64_t episodes() const { return episodes_; }
  // The current episode's world, by scenario name ("random-S", "dead_end-S").
  [[nodiscard]] const std::string& world_name() const { return scenario_.name; }
  // The objective selector's choice now (argmin G over P; -1 when P is empty): a baseline and
  // the fallback for a masked action.
  [[nodiscard]] int objective_action() const;
  [[nodiscard]] double robot_person_distance_m() const;

 private:
  [[nodiscard]] Scenario draw_scenario();  // a random world, or the dead end
  void new_world();
  void scan();  // the ray fan into the voxel grid, then the costmap
  void observe(std::span<float> observation, std::span<bool> mask);
  void move_robot(const core::Pose2& goal_world, const core::Point2& goal_velocity,
                  const core::Pose2& person_next, double dt_s);
  [[nodiscard]] double obstacle_clearance_m() const;  // robot centre to static and pedestrians
  [[nodiscard]] core::Pose2 person_estimate_base();

  FollowEnvConfig config_;
  std::mt19937_64 rng_;
  uint64_t episodes_ = 0;
  Scenario scenario_;
  Crowd crowd_;
  core::InteractiveSpace space_;
  core::StandoffVelocity standoff_velocity_;  // as the daemon's policy task has it
  core::VoxelGrid grid_;
  core::Costmap costmap_;
  std::vector<core::Ray> rays_;
  std::vector<MovingBody> bodies_;
  double t_s_ = 0, next_scan_s_ = 0;
  core::Pose2 robot_;     // world = odom
  core::Point2 robot_v_;  // world frame
  double robot_w_ = 0;
  core::Pose2 person_;
  core::Point2 person_v_;
  double person_w_ = 0;
  double far_s_ = 0;
  double previous_distance_m_ = 0;
  int previous_action_ = -1;
  core::HumanState human_;  // what the policy is told of the person (noisy)
  EpisodeStats episode_, last_episode_;
};

}  // namespace sim::training
