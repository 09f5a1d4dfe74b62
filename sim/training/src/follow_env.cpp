#include "sim/training/follow_env.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "core/policy/observation.hpp"
#include "firmware/daemon.hpp"
#include "firmware/lidar_pipeline.hpp"

namespace sim::training {
namespace {

double uniform(std::mt19937_64& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

double clamp_step(double current, double target, double max_change) {
  return current + std::clamp(target - current, -max_change, max_change);
}

core::Nanos nanos(double t_s) {
  return core::Nanos(static_cast<int64_t>(std::llround(t_s * 1e9)));
}

// Simulated seconds between physics steps inside one policy period (the control task's rate).
constexpr double kPhysicsStepS = 0.01;
// A change of the chosen point farther than this round W is a "jump" (EpisodeStats::jumps).
constexpr double kJumpM = 0.3;

}  // namespace

int wrapped_index_distance(int a, int b, int n) {
  if (n <= 0) return 0;
  const int d = std::abs(a - b) % n;
  return std::min(d, n - d);
}

Rewards step_rewards(const RewardConfig& c, double previous_distance_m, double distance_m,
                     int action, int previous_action, int points, double obstacle_clearance_m,
                     bool contact) {
  Rewards r;
  r.human = distance_m > c.tracking_distance_m
                ? c.sigma_h_per_m * (previous_distance_m - distance_m)
                : c.tracking_reward;
  if (previous_action >= 0 && action >= 0) {
    r.action = -c.sigma_a_per_index * wrapped_index_distance(action, previous_action, points);
  }
  if (contact || obstacle_clearance_m < c.safety_clearance_m) r.collision = c.collision_reward;
  return r;
}

FollowEnvConfig follow_env_config(const firmware::DaemonConfig& daemon) {
  FollowEnvConfig c;
  c.space = firmware::interactive_space_config(daemon);
  // The sizes the paper randomises over, round the configured ellipse (+-20 %, +-25 %).
  c.a_min_m = 0.8 * c.space.a_m;
  c.a_max_m = 1.2 * c.space.a_m;
  c.b_min_m = 0.75 * c.space.b_m;
  c.b_max_m = 1.25 * c.space.b_m;
  c.grid = firmware::voxel_grid_config(daemon);
  c.costmap = firmware::costmap_config(daemon);
  // The paper's min(L) >= R: the clearance at which the costmap reaches R.
  c.reward.safety_clearance_m = core::distance_at_cost(c.costmap, c.space.cost_threshold);
  c.barrier_delta = daemon.dcbf.delta;
  c.max_vx_mps = daemon.limits.vx_max_mps;
  c.max_vy_mps = daemon.limits.vy_max_mps;
  c.max_yaw_rate_radps = daemon.limits.wz_max_radps;
  c.accel_mps2 = daemon.limits.linear_accel_max_mps2;
  c.yaw_accel_radps2 = daemon.limits.angular_accel_max_radps2;
  return c;
}

FollowEnv::FollowEnv(const FollowEnvConfig& config, uint64_t seed)
    : config_(config),
      rng_(seed),
      space_(config.space),
      standoff_velocity_(config.space),
      grid_(config.grid) {
  rays_.reserve(static_cast<size_t>(config_.lidar_beams));
}

size_t FollowEnv::observation_size() const {
  return core::observation_size(static_cast<size_t>(config_.space.points));
}

Scenario FollowEnv::draw_scenario() {
  if (config_.dead_end_probability > 0 && uniform(rng_, 0, 1) < config_.dead_end_probability) {
    return make_scenario("dead_end", static_cast<uint32_t>(rng_())).value();
  }
  RandomScenarioOptions o;
  o.pedestrians = static_cast<int>(rng_() % static_cast<uint64_t>(config_.pedestrians_max + 1));
  o.obstacles = static_cast<int>(rng_() % static_cast<uint64_t>(config_.obstacles_max + 1));
  o.speed_min_mps = config_.speed_min_mps;
  o.speed_max_mps = config_.speed_max_mps;
  o.duration_s = config_.episode_s + 10.0;
  if (uniform(rng_, 0, 1) < config_.constrained_probability) {
    o.beside_walk_clearance_m =
        uniform(rng_, config_.beside_clearance_min_m, config_.beside_clearance_max_m);
  }
  return random_scenario(static_cast<uint32_t>(rng_()), o);
}

void FollowEnv::new_world() {
  scenario_ = draw_scenario();
  crowd_ = Crowd{};
  for (const Pedestrian& p : scenario_.pedestrians)
    crowd_.add(p);

  core::InteractiveSpaceConfig space = config_.space;
  space.a_m = uniform(rng_, config_.a_min_m, config_.a_max_m);
  space.b_m = std::min(uniform(rng_, config_.b_min_m, config_.b_max_m), space.a_m);
  space_ = core::InteractiveSpace(space);
  grid_ = core::VoxelGrid(config_.grid);

  t_s_ = 0;
  standoff_velocity_.reset();
  person_ = scenario_.person.pose_at(0);
  person_v_ = scenario_.person.velocity_at(0);
  person_w_ = 0;
  // The robot somewhere round the person, clear of the obstacles; else where the scenario says.
  robot_ = scenario_.robot_start;
  for (int attempt = 0; attempt < 50; ++attempt) {
    const double bearing = uniform(rng_, -std::numbers::pi, std::numbers::pi);
    const double r = uniform(rng_, config_.start_distance_min_m, config_.start_distance_max_m);
    const core::Pose2 candidate{person_.x_m + r * std::cos(bearing),
                                person_.y_m + r * std::sin(bearing),
                                core::wrap_angle(person_.theta_rad + uniform(rng_, -0.5, 0.5))};
    if (scenario_.world.distance({candidate.x_m, candidate.y_m}) > config_.robot_radius_m + 0.3) {
      robot_ = candidate;
      break;
    }
  }
  robot_v_ = {};
  robot_w_ = 0;
  far_s_ = 0;
  previous_action_ = -1;
  previous_distance_m_ = robot_person_distance_m();
  episode_ = {};
  ++episodes_;
  scan();
  next_scan_s_ = config_.lidar_period_s;
}

double FollowEnv::robot_person_distance_m() const {
  return std::hypot(person_.x_m - robot_.x_m, person_.y_m - robot_.y_m);
}

void FollowEnv::scan() {
  const double h = config_.sensor_height_m;
  const core::Point3 origin{robot_.x_m, robot_.y_m, h};
  const auto& people = crowd_.people();
  rays_.clear();
  for (int i = 0; i < config_.lidar_beams; ++i) {
    const double a = robot_.theta_rad + 2.0 * std::numbers::pi * i / config_.lidar_beams;
    const double dx = std::cos(a), dy = std::sin(a);
    const Point2 o{robot_.x_m, robot_.y_m};
    double range = config_.lidar_range_m;
    bool hit = false;
    if (const auto d = scenario_.world.ray(o, dx, dy, range)) {
      range = *d;
      hit = true;
    }
    auto body = [&](Point2 c, double radius) {
      if (const auto d = ray_circle(o, dx, dy, c, radius); d && *d < range) {
        range = *d;
        hit = true;
      }
    };
    for (const Pedestrian& p : people)
      body(p.position, p.radius_m);
    body({person_.x_m, person_.y_m}, scenario_.person_radius_m);
    const double end_range = hit ? range : config_.grid.clear_max_range_m;
    rays_.push_back({origin, {origin.x + end_range * dx, origin.y + end_range * dy, h}, hit});
  }
  const core::Nanos now = nanos(t_s_);
  grid_.recentre(robot_.x_m, robot_.y_m);
  grid_.insert(rays_, robot_,
               core::PersonSweep{{person_.x_m, person_.y_m}, {person_.x_m, person_.y_m}}, now);
  grid_.decay(now);
  costmap_.build(grid_, config_.costmap, now);
}

core::Pose2 FollowEnv::person_estimate_base() {
  std::normal_distribution<double> pos(0.0, config_.position_noise_m);
  std::normal_distribution<double> head(0.0, config_.heading_noise_rad);
  const core::Pose2 noisy{person_.x_m + pos(rng_), person_.y_m + pos(rng_),
                          core::wrap_angle(person_.theta_rad + head(rng_))};
  return robot_.inverse() * noisy;
}

void FollowEnv::observe(std::span<float> observation, std::span<bool> mask) {
  std::normal_distribution<double> vel(0.0, config_.velocity_noise_mps);
  human_ = {};
  human_.valid = true;
  human_.pose_base = person_estimate_base();
  human_.pose_odom = robot_ * human_.pose_base;
  human_.velocity_odom = {person_v_.x_m + vel(rng_), person_v_.y_m + vel(rng_)};
  human_.velocity_base = core::Pose2{0, 0, robot_.theta_rad}.inverse().apply(human_.velocity_odom);
  human_.yaw_rate_radps = person_w_;
  space_.update(
      human_.pose_base, robot_, costmap_,
      standoff_velocity_.base(human_.velocity_odom, human_.velocity_base, robot_, nanos(t_s_)));

  core::ObservationInputs in;
  in.space = &space_;
  in.costmap = &costmap_;
  in.robot_odom = robot_;
  const core::Point2 vb = core::Pose2{0, 0, robot_.theta_rad}.inverse().apply(robot_v_);
  in.robot_vx_mps = vb.x_m;
  in.robot_vy_mps = vb.y_m;
  in.robot_wz_radps = robot_w_;
  in.human = human_;
  in.previous_action = previous_action_;
  if (!core::build_observation(in, observation)) {
    throw std::invalid_argument("FollowEnv: the observation buffer is not observation_size()");
  }
  const auto cs = space_.candidates();
  for (size_t i = 0; i < mask.size(); ++i)
    mask[i] = i < cs.size() && cs[i].free;
}

void FollowEnv::reset(std::span<float> observation, std::span<bool> mask) {
  new_world();
  observe(observation, mask);
}

int FollowEnv::objective_action() const {
  const core::Selection s = core::select_by_objective(space_);
  return s.status == core::GoalStatus::kOk ? s.index : -1;
}

void FollowEnv::move_robot(const core::Pose2& goal, const core::Point2& goal_velocity,
                           const core::Pose2& person_next, double dt_s) {
  const double k = config_.steering_gain_per_s;
  const core::Point2 v_world{goal_velocity.x_m + k * (goal.x_m - robot_.x_m),
                             goal_velocity.y_m + k * (goal.y_m - robot_.y_m)};
  const double w_target = person_w_ + k * core::wrap_angle(goal.theta_rad - robot_.theta_rad);
  const core::Pose2 heading{0, 0, robot_.theta_rad};
  const core::Point2 target = heading.inverse().apply(v_world);
  const core::Point2 current = heading.inverse().apply(robot_v_);
  const double dv = config_.accel_mps2 * dt_s;
  const core::Twist nominal{
      std::clamp(clamp_step(current.x_m, target.x_m, dv), -config_.max_vx_mps, config_.max_vx_mps),
      std::clamp(clamp_step(current.y_m, target.y_m, dv), -config_.max_vy_mps, config_.max_vy_mps),
      std::clamp(clamp_step(robot_w_, w_target, config_.yaw_accel_radps2 * dt_s),
                 -config_.max_yaw_rate_radps, config_.max_yaw_rate_radps)};
  const auto& space = space_.config();
  const core::Twist u = core::repair(robot_, person_, person_next, nominal, dt_s,
                                     config_.barrier_delta, core::Ellipse{space.a_m, space.b_m},
                                     core::TwistLimits{config_.max_vx_mps, config_.max_vy_mps,
                                                       config_.max_yaw_rate_radps})
                            .u;
  const core::Point2 vb{u.vx, u.vy};
  robot_w_ = u.wz;
  // The barrier's model: body velocity at the heading now, then the turn.
  robot_v_ = core::Pose2{0, 0, robot_.theta_rad}.apply(vb);
  robot_.x_m += robot_v_.x_m * dt_s;
  robot_.y_m += robot_v_.y_m * dt_s;
  robot_.theta_rad = core::wrap_angle(robot_.theta_rad + robot_w_ * dt_s);
}

double FollowEnv::obstacle_clearance_m() const {
  const Point2 p{robot_.x_m, robot_.y_m};
  double d = scenario_.world.distance(p);
  for (const Pedestrian& q : crowd_.people()) {
    d = std::min(d, std::hypot(q.position.x_m - p.x_m, q.position.y_m - p.y_m) - q.radius_m);
  }
  return d;
}

StepResult FollowEnv::step(int action, std::span<float> observation, std::span<bool> mask) {
  StepResult result;
  const auto cs = space_.candidates();
  const bool valid = action >= 0 && static_cast<size_t>(action) < cs.size() &&
                     cs[static_cast<size_t>(action)].free;
  result.action_taken = valid ? action : objective_action();
  // q^d as a point of W on the person (the daemon carries it along the person the same way).
  bool has_goal = result.action_taken >= 0;
  core::Pose2 goal_in_person;
  if (has_goal) {
    const core::Pose2 person_base = human_.pose_base;
    goal_in_person = person_base.inverse() * cs[static_cast<size_t>(result.action_taken)].base;
  }

  bool contact = false;
  double near_s = 0;
  const double end_s = t_s_ + config_.policy_period_s;
  while (t_s_ < end_s - 1e-9) {
    const double dt = std::min(kPhysicsStepS, end_s - t_s_);
    const core::Pose2 person_next = scenario_.person.pose_at(t_s_ + dt);
    person_w_ = core::wrap_angle(person_next.theta_rad - person_.theta_rad) / dt;
    person_v_ = scenario_.person.velocity_at(t_s_ + dt);
    if (has_goal) {
      const core::Pose2 goal = person_ * goal_in_person;
      const core::Point2 r = person_.rotate({goal_in_person.x_m, goal_in_person.y_m});
      const core::Point2 goal_v{person_v_.x_m - person_w_ * r.y_m,
                                person_v_.y_m + person_w_ * r.x_m};
      move_robot(goal, goal_v, person_next, dt);
    } else {
      move_robot(robot_, {}, person_next, dt);  // no free point: brake where it is
    }
    t_s_ += dt;
    person_ = person_next;
    bodies_.assign({MovingBody{{person_.x_m, person_.y_m}, person_v_, scenario_.person_radius_m},
                    MovingBody{{robot_.x_m, robot_.y_m}, robot_v_, 0.45}});
    crowd_.step(dt, scenario_.world, bodies_);
    const double clearance = obstacle_clearance_m();
    if (clearance < config_.reward.safety_clearance_m) near_s += dt;
    const bool person_contact = robot_person_distance_m() < config_.intimate_m;
    if (clearance < config_.robot_radius_m || person_contact) {
      contact = true;
      episode_.contact_person = person_contact;
      break;
    }
    if (t_s_ >= next_scan_s_) {
      scan();
      next_scan_s_ += config_.lidar_period_s;
    }
  }

  const double distance = robot_person_distance_m();
  far_s_ = distance > config_.far_m ? far_s_ + config_.policy_period_s : 0.0;
  const bool lost = far_s_ > config_.far_max_s;
  result.rewards =
      step_rewards(config_.reward, previous_distance_m_, distance, result.action_taken,
                   previous_action_, config_.space.points, obstacle_clearance_m(), contact);
  if (previous_action_ >= 0 && result.action_taken >= 0 &&
      previous_action_ != result.action_taken) {
    // The distance between the two points of W in the person's frame (docs/EVALUATION.md counts
    // the same in the closed loop's samples).
    const core::Point2 p = space_.point_in_person(static_cast<size_t>(previous_action_));
    const core::Point2 q = space_.point_in_person(static_cast<size_t>(result.action_taken));
    if (std::hypot(p.x_m - q.x_m, p.y_m - q.y_m) > kJumpM) ++episode_.jumps;
  }
  previous_distance_m_ = distance;
  previous_action_ = result.action_taken;
  result.terminated = contact || lost;
  result.truncated = !result.terminated && t_s_ >= config_.episode_s - 1e-9;

  episode_.return_sum += result.rewards.total();
  episode_.steps += 1;
  episode_.duration_s = t_s_;
  episode_.contact = episode_.contact || contact;
  episode_.lost = episode_.lost || lost;
  episode_.near_obstacle_s += near_s;
  if (result.terminated || result.truncated) {
    last_episode_ = episode_;
    reset(observation, mask);
  } else {
    observe(observation, mask);
  }
  return result;
}

}  // namespace sim::training
