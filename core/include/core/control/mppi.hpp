#pragma once
// MPPI with a discrete-time CBF cost (paper, section V), on the robot's planar pose in odom.
//   state (x, y, theta), control (vx, vy, wz) in the body frame, Euler steps of dt:
//     x += (vx cos th - vy sin th) dt,  y += (vx sin th + vy cos th) dt,  th += wz dt
//   per step k: tracking (q_k - q^d_k)^T Q (q_k - q^d_k), the error expressed in the goal's frame
//   (e_x along the goal heading, e_y across it) or the robot's at the start (TrackingFrame),
//   e_theta wrapped; c_collision when the costmap
//   cost (bilinear) >= R (c_contact instead where the footprint can touch); c_safe max((1 - delta)
//   h_k - h_{k+1}, 0) with h the ellipse barrier around the person's PREDICTED pose at step k; the
//   control cost lambda u^T Sigma^-1 eps; a terminal tracking cost at K. Sampled controls are
//   limited to the velocity box and to what the base's accelerations reach from the previous
//   control. weights w_m = exp(-(S_m - min S) / lambda); the mean sequence moves by the weighted
//   noise.
// Warm start: the previous mean shifted by the elapsed time (fractionally: the controller runs
// every 10 ms while a step is 100 ms), optional smoothing. Noise comes from a pre-generated
// pool of standard normals (offsets drawn per sample), so it is cheap and reproducible.
// Samples are evaluated in parallel with OpenMP. NaN anywhere -> zero command and a failure.
#include <cstdint>
#include <span>
#include <vector>

#include "core/control/closing_speed.hpp"
#include "core/control/costmap_path.hpp"
#include "core/control/dcbf_repair.hpp"
#include "core/control/obstacle_speed.hpp"
#include "core/geometry/pose2.hpp"
#include "core/perception/costmap.hpp"
#include "core/time.hpp"

namespace core {

// The frame the tracking error is expressed in before Q weighs it.
enum class TrackingFrame {
  kGoal,   // q^d's at each step: e_x along the goal's (the person's) heading
  kRobot,  // the robot's at the start of the rollouts (base_link when planning)
};

struct MppiConfig {
  int horizon_steps = 100;  // K
  double step_s = 0.1;      // dt
  int samples = 2000;       // M
  double lambda = 1.0;
  // Floor on 1/sum(w^2): lambda is raised (per update) until this many samples carry the update;
  // 0 keeps lambda. See MppiOutput::lambda.
  int min_effective_samples = 0;
  std::array<double, 3> sigma = {0.3, 0.3, 0.5};  // noise std of vx, vy, wz
  std::array<double, 3> q = {50.0, 10.0, 20.0};   // Q = diag(c_x, c_y, c_theta)
  TrackingFrame tracking_frame = TrackingFrame::kGoal;
  double terminal_weight = 2.0;  // the terminal cost is this times Q's
  double collision_cost = 1000.0;
  double cost_threshold = 30.0;  // R
  // A second tier, not in the paper: a predicted state whose costmap cost is >= contact_threshold
  // (where the footprint can touch an obstacle: the cost at its circumscribed radius) costs
  // contact_cost instead of collision_cost. With c_collision alone, crossing a few steps of the
  // unsafe band costs less than lagging a metre behind q^d over the horizon, and the best plan
  // can run the robot into the obstacle itself. 0: off (the paper's single tier).
  double contact_cost = 0.0;
  double contact_threshold = 100.0;
  double dcbf_delta = 0.5;
  double c_safe = 5000.0;
  Ellipse ellipse;
  TwistLimits limits;
  // The plan's largest backward speed (m/s; not in the paper; Nav2's MPPI has vx_min): the
  // samples and the mean reverse no faster than this (nor than limits.vx). The barrier's repair
  // and the closing-speed limit may still back the robot off up to limits.vx: they keep the
  // person safe. Among pedestrians walking at the robot, a plan free to reverse backs away from
  // them, and from the person, at full speed; a slower reverse leaves stepping aside the cheaper
  // way (docs/eval/SESSIONS.md, twenty-eighth session).
  double reverse_speed_max_mps = 3.0;
  // Speed and separation toward the person, applied to the repaired command (closing_speed.hpp;
  // robot_decel_mps2 = 0: off).
  ClosingSpeedConfig closing;
  // Speed and separation toward obstacles, applied after it (obstacle_speed.hpp; not in the
  // paper; robot_decel_mps2 = 0: off).
  ObstacleSpeedConfig obstacle_speed;
  double linear_accel_mps2 = 1.5;  // applied to the output command
  double angular_accel_radps2 = 3.0;
  bool smooth = true;  // 3-tap smoothing of the updated mean sequence
  // Eight structured samples beside the M random ones (not in the paper): the mean itself, a
  // full brake, and a feedback law that steers to q^d's path at full and at half speed (the
  // rest random). Random noise about a warm-started mean explores a few tenths of a m/s: when
  // the person turns sharply while the robot is fast, no random sample brakes and turns in
  // time, and the update keeps the robot on a wide loop away from them. The structured samples
  // are not averaged in (any weight would pull the plan toward them, better or not): the best
  // of them becomes the plan when it costs less than every random sample.
  bool guide_samples = false;
  // A ninth structured sample (with guide_samples; not in the paper): when the robot's straight
  // line to q^d, or q^d's own way over the horizon, runs where the footprint would touch (the
  // contact tier's cost; the lethal core without it), the costmap's shortest path round it to
  // q^d at the horizon's end (costmap_path.hpp), followed by the steering law on a carrot that
  // runs along it at path_speed_mps but never has less left to go than q^d has. Random samples
  // explore a few tenths of a metre about the last plan, and the steering law goes where q^d
  // goes, so round a cluster of obstacles the plan keeps the side it first found, the long one
  // too, and where the person passes close by an obstacle the law runs into it. Scored like the
  // others; becomes the plan only when it beats every random sample.
  bool path_guide = false;
  CostmapPathConfig path;  // its unsafe_cost is cost_threshold (R), whatever it says
  double path_cell_m = 0.1;
  double path_speed_mps = 1.0;  // 1.5 cut the corner round a wall end into the contact tier
  // One more structured sample (with guide_samples; not in the paper): when the robot's straight
  // line to q^d runs deep through the person's ellipse (q^d on their other side: the chord's
  // nearest point inside orbit_trigger_radius of the ellipse, in its normalised radius), the
  // steering law on a carrot that goes round the person, round their back (never in front of
  // them), at orbit_radius times the ellipse and orbit_speed_mps, then onto q^d. The barrier
  // forbids the straight way and random samples about a plan that holds still do not reach round:
  // the robot stays on the side it first took, with q^d across the person (the fixed_side
  // baseline's e_y of ~1 m).
  double orbit_trigger_radius = 0.85;
  // The steering law's pull toward q^d's heading (1/s; its turn rate feeds forward besides): 2
  // turns a 0.5 rad lag back at 1 rad/s. With the structured samples the plan most of the time
  // (~87 % of the control steps on the random worlds), this is how fast the robot answers a
  // person's turn (docs/eval/SESSIONS.md, thirty-seventh session).
  double guide_heading_gain_per_s = 2.0;
  double orbit_radius = 1.15;
  double orbit_speed_mps = 1.0;
  bool orbit_guide = false;  // (after its parameters: beside `threads`, no padding)
  int threads = 2;
  uint64_t seed = 1;
};

struct MppiInputs {
  Pose2 robot;                       // odom
  Twist current;                     // the last command (for the acceleration limit)
  Pose2 goal;                        // q^d in odom
  std::span<const Pose2> person;     // predicted person poses at steps 0..K (odom); may be empty
  const Costmap* costmap = nullptr;  // may be null (no collision cost)
  Nanos now{0};
  // q^d at steps 0..K (odom) when it moves with the person (the interactive space is attached
  // to them); empty: `goal` at every step.
  std::span<const Pose2> goal_path;
  // q^d's heading at steps 0..K when it turns on its own (predict_goal_headings); empty: each
  // step's goal_path heading. Only the heading target: the frame the position error is weighed
  // in (tracking_frame kGoal) stays goal_path's, the person's predicted way.
  std::span<const double> goal_heading_path;
};

// The best rollout's cost by term (they sum to its total): what the controller is trading off.
// A collision term of n x collision_cost means its best plan crosses n steps of lethal costmap;
// a barrier term, that it enters the person's ellipse faster than the DCBF allows.
struct MppiCostTerms {
  double tracking = 0;   // stage + terminal tracking of q^d
  double collision = 0;  // collision_cost per step at costmap cost >= R (contact_cost in contact)
  double barrier = 0;    // c_safe max((1 - delta) h_k - h_{k+1}, 0)
  double control = 0;    // lambda u^T Sigma^-1 eps (may be negative)
};

struct MppiOutput {
  Twist command;    // repaired and limited
  Twist nominal;    // the first control of the optimised mean, before repair
  bool ok = false;  // false: numerical failure, command is zero
  bool repaired = false;
  bool repair_feasible = true;
  bool closing_limited = false;   // slowed toward the person (ClosingSpeedConfig)
  bool obstacle_limited = false;  // slowed to stop short of an obstacle (ObstacleSpeedConfig)
  bool guided = false;            // a structured sample beat every random one and became the plan
  bool path_planned = false;     // an obstacle lay on the line to q^d and a path round it was found
  bool path_guided = false;      // ... and its sample became the plan
  bool orbit_planned = false;    // q^d lay across the person's ellipse: the orbit sample ran
  bool orbit_guided = false;     // ... and it became the plan
  double min_cost = 0;           // best sample's cost
  MppiCostTerms best;            // ... by term
  double effective_samples = 0;  // 1 / sum(w^2): how many samples carried the update
  double lambda = 0;             // the temperature used (>= config lambda)
};

class Mppi {
 public:
  explicit Mppi(const MppiConfig& config);

  MppiOutput step(const MppiInputs& in);
  void reset();  // forget the warm start (e.g. after a stop)

  [[nodiscard]] const MppiConfig& config() const { return cfg_; }
  [[nodiscard]] std::span<const Twist> mean() const { return mean_; }

 private:
  static constexpr size_t kLanes = 8;  // samples per vectorised block (M is rounded up)
  void shift_mean(Nanos now);
  void rollout_block(size_t block, const MppiInputs& in);
  void prepare_guide_block(const MppiInputs& in);
  // The kLanes noise values of a block at step k, dimension d (standard normals: u = mean +
  // sigma n).
  [[nodiscard]] const float* noise_row(size_t block, size_t k, size_t d) const;

  MppiConfig cfg_;
  std::vector<Twist> mean_;       // K controls
  std::vector<Twist> scratch_;    // K controls (shift / smoothing)
  std::vector<Twist> update_;     // K: the weighted noise the mean moves by
  std::vector<float> pool_;       // standard normals
  std::vector<uint32_t> offset_;  // per block of kLanes samples: where its noise starts
  // The structured samples' block (the last one; none when guide_samples is off) and its noise,
  // laid out as a pool block: (k * 3 + d) * kLanes + lane.
  size_t guide_block_ = SIZE_MAX;
  std::vector<float> guide_noise_;
  // Lanes 0 .. structured_lanes_ - 1 of the guide block are structured (not averaged in): 4,
  // then the path sample when a path was planned this step, then the orbit sample when q^d is
  // across the person; their lanes (kNoLane: none this step).
  static constexpr size_t kNoLane = SIZE_MAX;
  size_t structured_lanes_ = 4;
  size_t path_lane_ = kNoLane;
  size_t orbit_lane_ = kNoLane;
  CostmapPathPlanner planner_;
  std::vector<Point2> path_;      // robot -> q^d round the obstacles; empty: no path sample
  std::vector<double> path_arc_;  // arc length along path_ at each of its points
  std::vector<double> goal_arc_;  // arc length along q^d's path at each goal frame
  std::vector<double> cost_;      // per sample
  std::vector<float> tracking_cost_, collision_cost_, barrier_cost_;  // per sample, by term
  std::vector<double> weight_;                                        // per sample
  std::vector<uint32_t> active_;  // samples that carry weight (capacity M: no allocation)
  ObstacleSpeedLimit obstacle_limit_;
  uint64_t rng_state_;
  // Prepared once per step for the rollouts.
  struct PersonFrame {
    double x, y, c, s;  // predicted person position and heading cos/sin (odom)
  };
  std::vector<PersonFrame> person_frames_;  // K + 1 (capacity fixed at construction)
  struct GoalFrame {
    double x, y, theta, c, s;  // q^d at a step, its heading and its frame's cos/sin
  };
  std::vector<GoalFrame> goal_frames_;  // 1 or K + 1 (capacity fixed at construction)
  double robot_cos_ = 1, robot_sin_ = 0;
  bool has_time_ = false;
  Nanos last_{0};
};

}  // namespace core
