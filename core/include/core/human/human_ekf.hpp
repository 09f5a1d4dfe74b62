#pragma once
// The tracked person's planar state in `odom`: a Kalman filter with a constant-velocity model
// in position and heading, state s = [x, y, theta, vx, vy, omega] (m, rad, m/s, rad/s).
// Measurements: the tracker's person pose (already moved into odom with the robot's odometry at
// the measurement time; heading optional) and, optionally, the worn sensor's yaw rate. Outliers
// are rejected by a Mahalanobis gate; a run of rejections (the person really is elsewhere, e.g.
// after a tracking gap) re-initialises the track. Pure: time is an argument; no allocation.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <optional>
#include <span>

#include "core/geometry/pose2.hpp"
#include "core/safety/supervisor.hpp"  // TrackerConfidence
#include "core/time.hpp"

namespace core {

struct HumanEkfConfig {
  double position_noise_m = 0.05;     // 1-sigma of one tracker position
  double heading_noise_rad = 0.10;    // 1-sigma of one tracker heading
  double yaw_rate_noise_radps = 0.2;  // 1-sigma of one gyro yaw rate
  // White-noise acceleration of the constant-velocity model: the filter's bandwidth. Higher
  // follows sudden stops faster, lower gives a smoother velocity (see test_human_ekf).
  double accel_noise_mps2 = 0.5;
  double yaw_accel_noise_radps2 = 2.0;
  double gate_probability = 0.999;    // chi-square gate: 0.99, 0.995 or 0.999
  uint32_t reset_after_rejects = 12;  // consecutive rejected poses (100 ms at 120 Hz)
  Nanos reset_after_gap = std::chrono::milliseconds(1000);  // no accepted pose this long
  double initial_speed_sigma_mps = 1.5;
  double initial_yaw_rate_sigma_radps = 1.5;
  // Prediction of where q^d will be over the controller's horizon (predict_path): the person's
  // velocity is known now and less and less later. A first-order Markov (Singer) velocity with
  // this time constant predicts the displacement v tau (1 - exp(-t / tau)): constant velocity at
  // first, at most v tau in all. 0: constant velocity over the whole horizon.
  double prediction_time_constant_s = 0.0;
  // The same for the person's turn rate (0: as the velocity: prediction_time_constant_s for
  // q^d's path, constant for the barrier's person). See predict_path.
  double prediction_turn_time_constant_s = 0.0;
  // How long the turn rate lasts in q^d's heading alone (0: as its position, the line above;
  // predict_goal_headings). A mecanum base turns without moving: the heading it is asked for over
  // the horizon can fade sooner than the carrier that places q^d and orients its error
  // (docs/eval/SESSIONS.md, forty-first session).
  double prediction_heading_turn_time_constant_s = 0.0;
};

using HumanVector = Eigen::Matrix<double, 6, 1>;
using HumanCovariance = Eigen::Matrix<double, 6, 6>;

// The filter's state at `stamp`: a plain, trivially copyable value (it travels through
// latest-value channels); other tasks predict it to their own query time with predict_track().
struct HumanTrack {
  bool valid = false;
  std::array<double, 6> mean_data{};         // [x, y, theta, vx, vy, omega]
  std::array<double, 36> covariance_data{};  // 6 x 6, column-major
  Nanos stamp{0};                            // time of the mean
  Nanos last_update{0};                      // time of the latest accepted pose

  Eigen::Map<HumanVector> mean() { return Eigen::Map<HumanVector>(mean_data.data()); }
  [[nodiscard]] Eigen::Map<const HumanVector> mean() const {
    return Eigen::Map<const HumanVector>(mean_data.data());
  }
  Eigen::Map<HumanCovariance> covariance() {
    return Eigen::Map<HumanCovariance>(covariance_data.data());
  }
  [[nodiscard]] Eigen::Map<const HumanCovariance> covariance() const {
    return Eigen::Map<const HumanCovariance>(covariance_data.data());
  }
};

struct HumanEkfCounters {
  uint64_t updates = 0;
  uint64_t rejected = 0;  // by the gate
  uint64_t resets = 0;    // re-initialisations (the first one included)
  uint64_t yaw_rate_updates = 0;
  uint64_t invalid_inputs = 0;  // NaN/Inf measurements, time going backwards
};

enum class UpdateResult : uint8_t { kAccepted, kRejected, kReset, kInvalid };

class HumanEkf {
 public:
  explicit HumanEkf(const HumanEkfConfig& config);

  // Person pose in odom at `stamp`. `heading_valid` false: position only.
  UpdateResult update_pose(const Pose2& person_in_odom, bool heading_valid, Nanos stamp);
  // Yaw rate of the person (rad/s, about z) at `stamp`, from the worn sensor's gyro: taken unless
  // no person turns that fast (10 rad/s; not the poses' chi-square gate: a gyro is inertial).
  UpdateResult update_yaw_rate(double yaw_rate_radps, Nanos stamp);

  [[nodiscard]] const HumanTrack& track() const { return track_; }
  [[nodiscard]] const HumanEkfCounters& counters() const { return counters_; }
  // Squared Mahalanobis distance of the latest pose innovation (for diagnostics).
  [[nodiscard]] double last_nis() const { return last_nis_; }

 private:
  void predict_to(Nanos t);
  void reset(const Pose2& z, bool heading_valid, Nanos stamp);

  HumanEkfConfig config_;
  HumanTrack track_;
  HumanEkfCounters counters_;
  uint32_t consecutive_rejects_ = 0;
  double last_nis_ = 0;
};

// The track moved forward (or backward) to `t` with the model; covariance grows with |dt|.
HumanTrack predict_track(const HumanTrack& track, Nanos t, const HumanEkfConfig& config);

// The person's predicted pose at t0, t0 + dt, ... (out.size() poses): the track's velocity
// fading with `time_constant_s` after the track's stamp (0: constant velocity; see
// HumanEkfConfig::prediction_time_constant_s), its turn rate with `turn_time_constant_s` (0:
// constant turn rate). A turn rate measured mid-turn and carried on for seconds turns the
// predicted person round and round: a person's turn lasts about a second.
void predict_path(const HumanTrack& track, Nanos t0, double dt_s, double time_constant_s,
                  double turn_time_constant_s, std::span<Pose2> out);
// What the controller predicts over its horizon, one rule for every caller: `person`, for the
// barrier, at constant velocity and turn rate (the conservative place they may be); `goal`, q^d's
// path: the chosen point held in the frame of a carrier person whose velocity fades as
// config.prediction_time_constant_s and whose turn rate fades as
// config.prediction_turn_time_constant_s (0: as the velocity; `goal_in_person`: q^d in the frame
// of the person it was chosen for); a q^d ahead of the person (x > 0) rides the barrier's person
// instead, so the barrier's person never walks into it.
void predict_person_and_goal_paths(const HumanTrack& track, Nanos t0, double dt_s,
                                   const HumanEkfConfig& config, const Pose2& goal_in_person,
                                   std::span<Pose2> person, std::span<Pose2> goal);
// q^d's heading alone at t0, t0 + dt, ... (out.size() values): the person's heading turning at
// the track's turn rate faded with `turn_time_constant_s`, plus q^d's heading in the person's
// frame (HumanEkfConfig::prediction_heading_turn_time_constant_s; MppiInputs::goal_heading_path).
void predict_goal_headings(const HumanTrack& track, Nanos t0, double dt_s,
                           double turn_time_constant_s, double goal_heading_in_person_rad,
                           std::span<double> out);
// The person's position at t (before or after the track's stamp), constant velocity.
Point2 position_at(const HumanTrack& track, Nanos t);

// What the planner and the controller consume.
struct HumanState {
  bool valid = false;
  Pose2 pose_odom;
  Point2 velocity_odom;  // m/s
  double yaw_rate_radps = 0;
  Pose2 pose_base;       // person in base_link
  Point2 velocity_base;  // the person's velocity (over ground) in base_link axes
  std::array<double, 9> pose_covariance_odom{};  // (x, y, theta), row-major, at the query time
  double position_sigma_m = 0;  // sqrt of the largest eigenvalue of the position covariance
  double heading_sigma_rad = 0;
  Nanos age{0};  // time since the latest accepted tracker pose
  // The tracker's confidence (the gate's verdict) at the query time; set by whoever holds it,
  // the filter does not know it.
  TrackerConfidence confidence = TrackerConfidence::kUnknown;
};
HumanState human_state(const HumanTrack& track, Nanos t, const Pose2& base_in_odom,
                       const HumanEkfConfig& config,
                       TrackerConfidence confidence = TrackerConfidence::kUnknown);

}  // namespace core
