#include "core/human/human_ekf.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>

namespace core {
namespace {

// Chi-square quantiles for 1..3 degrees of freedom.
double chi2_threshold(double probability, int dof) {
  struct Row {
    double p;
    std::array<double, 3> q;
  };
  static constexpr std::array<Row, 3> kTable = {{
      {0.99, {6.635, 9.210, 11.345}},
      {0.995, {7.879, 10.597, 12.838}},
      {0.999, {10.828, 13.816, 16.266}},
  }};
  const Row* best = &kTable[2];
  for (const Row& r : kTable) {
    if (std::abs(r.p - probability) < std::abs(best->p - probability)) best = &r;
  }
  return best->q[static_cast<size_t>(std::clamp(dof, 1, 3) - 1)];
}

bool finite(const Pose2& p) {
  return std::isfinite(p.x_m) && std::isfinite(p.y_m) && std::isfinite(p.theta_rad);
}

// Joseph-form update with measurement matrix rows picked from the state (H is a selection).
template <int M>
double innovation_nis(const HumanTrack& t, const std::array<int, M>& rows,
                      const Eigen::Matrix<double, M, 1>& z, const Eigen::Matrix<double, M, M>& r,
                      Eigen::Matrix<double, M, 1>& nu, Eigen::Matrix<double, M, M>& s) {
  for (int i = 0; i < M; ++i) {
    nu(i) = z(i) - t.mean()(rows[static_cast<size_t>(i)]);
    if (rows[static_cast<size_t>(i)] == 2) nu(i) = wrap_angle(nu(i));
    for (int j = 0; j < M; ++j) {
      s(i, j) = t.covariance()(rows[static_cast<size_t>(i)], rows[static_cast<size_t>(j)]);
    }
  }
  s += r;
  // S is at most 3x3 and positive definite: Eigen's closed-form inverse is exact and cheap.
  return nu.dot(s.inverse() * nu);
}

template <int M>
void apply_update(HumanTrack& t, const std::array<int, M>& rows,
                  const Eigen::Matrix<double, M, 1>& nu, const Eigen::Matrix<double, M, M>& s,
                  const Eigen::Matrix<double, M, M>& r) {
  Eigen::Matrix<double, M, 6> h = Eigen::Matrix<double, M, 6>::Zero();
  for (int i = 0; i < M; ++i)
    h(i, rows[static_cast<size_t>(i)]) = 1.0;
  const Eigen::Matrix<double, 6, M> pht = t.covariance() * h.transpose();
  const Eigen::Matrix<double, 6, M> k = pht * s.inverse();
  t.mean() += k * nu;
  t.mean()(2) = wrap_angle(t.mean()(2));
  const HumanCovariance ikh = HumanCovariance::Identity() - k * h;
  const HumanCovariance c = ikh * t.covariance() * ikh.transpose() + k * r * k.transpose();
  t.covariance() = 0.5 * (c + c.transpose());  // (a temporary: no aliasing with the transpose)
}

// Seconds of motion at the current rate that a prediction fading with tau amounts to by t (the
// integral of exp(-t / tau)); tau 0 keeps the rate; before the stamp (t < 0) the track's own
// constant-rate model.
double faded_s(double t, double tau) {
  return tau > 0.0 && t > 0.0 ? tau * -std::expm1(-t / tau) : t;
}

}  // namespace

HumanTrack predict_track(const HumanTrack& track, Nanos t, const HumanEkfConfig& config) {
  HumanTrack out = track;
  if (!track.valid) return out;
  const double dt = to_seconds(t - track.stamp);
  if (dt == 0.0) return out;
  HumanCovariance f = HumanCovariance::Identity();
  f(0, 3) = f(1, 4) = f(2, 5) = dt;
  out.mean() = f * track.mean();
  out.mean()(2) = wrap_angle(out.mean()(2));
  // Continuous white-noise acceleration, integrated over |dt|.
  const double a = std::abs(dt);
  const double q3 = a * a * a / 3.0;
  const double q2 = a * a / 2.0 * (dt < 0 ? -1.0 : 1.0);
  HumanCovariance q = HumanCovariance::Zero();
  const std::array<double, 3> spectral = {
      config.accel_noise_mps2 * config.accel_noise_mps2,
      config.accel_noise_mps2 * config.accel_noise_mps2,
      config.yaw_accel_noise_radps2 * config.yaw_accel_noise_radps2};
  for (int i = 0; i < 3; ++i) {
    const double sd = spectral[static_cast<size_t>(i)];
    q(i, i) = q3 * sd;
    q(i, i + 3) = q(i + 3, i) = q2 * sd;
    q(i + 3, i + 3) = a * sd;
  }
  out.covariance() = f * track.covariance() * f.transpose() + q;
  out.stamp = t;
  return out;
}

void predict_path(const HumanTrack& track, Nanos t0, double dt_s, double time_constant_s,
                  double turn_time_constant_s, std::span<Pose2> out) {
  const double t0_s = to_seconds(t0 - track.stamp);
  for (size_t k = 0; k < out.size(); ++k) {
    const double t = t0_s + dt_s * static_cast<double>(k);
    const double s = faded_s(t, time_constant_s);
    const double s_turn = faded_s(t, turn_time_constant_s);
    out[k] = Pose2{track.mean()(0) + track.mean()(3) * s, track.mean()(1) + track.mean()(4) * s,
                   wrap_angle(track.mean()(2) + track.mean()(5) * s_turn)};
  }
}

void predict_person_and_goal_paths(const HumanTrack& track, Nanos t0, double dt_s,
                                   const HumanEkfConfig& config, const Pose2& goal_in_person,
                                   std::span<Pose2> person, std::span<Pose2> goal) {
  // The barrier's person: constant velocity and turn rate, the conservative place they may be
  // (a person turning round toward the robot is predicted near it; faded, they walk off).
  predict_path(track, t0, dt_s, 0.0, 0.0, person);
  const double turn_s = config.prediction_turn_time_constant_s;
  const double tau_s = config.prediction_time_constant_s;
  // A q^d ahead of the person (the robot leads) rides the barrier's person: on a faded carrier
  // the barrier's person would walk into it within seconds, and the robot, told to wait there,
  // stops in front of a walking person (the dead ends of docs/EVALUATION.md). Behind or beside
  // them a faded q^d only lags, which is safe. (The point straight beside them is x ~ 1e-16 m
  // by rounding: the margin keeps it beside.)
  constexpr double kAheadM = 0.05;
  const bool leading = goal_in_person.x_m > kAheadM;
  if (!leading && (tau_s > 0.0 || turn_s > 0.0)) {
    predict_path(track, t0, dt_s, tau_s, turn_s > 0.0 ? turn_s : tau_s, goal);
  } else {  // nothing fades: the barrier's prediction, without a second pass
    std::copy_n(person.begin(), std::min(person.size(), goal.size()), goal.begin());
  }
  for (Pose2& g : goal)
    g = g * goal_in_person;
}

void predict_goal_headings(const HumanTrack& track, Nanos t0, double dt_s,
                           double turn_time_constant_s, double goal_heading_in_person_rad,
                           std::span<double> out) {
  const double t0_s = to_seconds(t0 - track.stamp);
  for (size_t k = 0; k < out.size(); ++k) {
    const double t = t0_s + dt_s * static_cast<double>(k);
    out[k] = wrap_angle(track.mean()(2) + track.mean()(5) * faded_s(t, turn_time_constant_s) +
                        goal_heading_in_person_rad);
  }
}

Point2 position_at(const HumanTrack& track, Nanos t) {
  const double dt = to_seconds(t - track.stamp);
  return Point2{track.mean()(0) + track.mean()(3) * dt, track.mean()(1) + track.mean()(4) * dt};
}

HumanEkf::HumanEkf(const HumanEkfConfig& config) : config_(config) {}

void HumanEkf::predict_to(Nanos t) {
  if (t > track_.stamp) track_ = predict_track(track_, t, config_);
}

void HumanEkf::reset(const Pose2& z, bool heading_valid, Nanos stamp) {
  track_.valid = true;
  track_.mean() << z.x_m, z.y_m, heading_valid ? wrap_angle(z.theta_rad) : 0.0, 0, 0, 0;
  track_.covariance_data.fill(0.0);
  const double sp = config_.position_noise_m * config_.position_noise_m;
  track_.covariance()(0, 0) = track_.covariance()(1, 1) = sp;
  // Without a heading, the heading is unknown: a wide prior (a full turn).
  track_.covariance()(2, 2) =
      heading_valid ? config_.heading_noise_rad * config_.heading_noise_rad : 10.0;
  track_.covariance()(3, 3) = track_.covariance()(4, 4) =
      config_.initial_speed_sigma_mps * config_.initial_speed_sigma_mps;
  track_.covariance()(5, 5) =
      config_.initial_yaw_rate_sigma_radps * config_.initial_yaw_rate_sigma_radps;
  track_.stamp = stamp;
  track_.last_update = stamp;
  consecutive_rejects_ = 0;
  last_nis_ = 0;
  ++counters_.resets;
}

UpdateResult HumanEkf::update_pose(const Pose2& z, bool heading_valid, Nanos stamp) {
  if (!finite(z) || (track_.valid && stamp < track_.stamp)) {
    ++counters_.invalid_inputs;
    return UpdateResult::kInvalid;
  }
  if (!track_.valid || stamp - track_.last_update > config_.reset_after_gap) {
    reset(z, heading_valid, stamp);
    return UpdateResult::kReset;
  }
  predict_to(stamp);
  const double sp = config_.position_noise_m * config_.position_noise_m;
  bool accepted = false;
  if (heading_valid) {
    const std::array<int, 3> rows = {0, 1, 2};
    const Eigen::Vector3d zz(z.x_m, z.y_m, z.theta_rad);
    const Eigen::Matrix3d r =
        Eigen::Vector3d(sp, sp, config_.heading_noise_rad * config_.heading_noise_rad).asDiagonal();
    Eigen::Vector3d nu;
    Eigen::Matrix3d s;
    last_nis_ = innovation_nis<3>(track_, rows, zz, r, nu, s);
    accepted = last_nis_ <= chi2_threshold(config_.gate_probability, 3);
    if (accepted) apply_update<3>(track_, rows, nu, s, r);
  } else {
    const std::array<int, 2> rows = {0, 1};
    const Eigen::Vector2d zz(z.x_m, z.y_m);
    const Eigen::Matrix2d r = Eigen::Vector2d(sp, sp).asDiagonal();
    Eigen::Vector2d nu;
    Eigen::Matrix2d s;
    last_nis_ = innovation_nis<2>(track_, rows, zz, r, nu, s);
    accepted = last_nis_ <= chi2_threshold(config_.gate_probability, 2);
    if (accepted) apply_update<2>(track_, rows, nu, s, r);
  }
  if (accepted) {
    track_.last_update = stamp;
    consecutive_rejects_ = 0;
    ++counters_.updates;
    return UpdateResult::kAccepted;
  }
  ++counters_.rejected;
  if (++consecutive_rejects_ >= config_.reset_after_rejects) {
    reset(z, heading_valid, stamp);
    return UpdateResult::kReset;
  }
  return UpdateResult::kRejected;
}

UpdateResult HumanEkf::update_yaw_rate(double yaw_rate_radps, Nanos stamp) {
  if (!std::isfinite(yaw_rate_radps) || !track_.valid || stamp < track_.stamp) {
    ++counters_.invalid_inputs;
    return UpdateResult::kInvalid;
  }
  predict_to(stamp);
  const std::array<int, 1> rows = {5};
  Eigen::Matrix<double, 1, 1> z;
  z << yaw_rate_radps;
  Eigen::Matrix<double, 1, 1> r;
  r << config_.yaw_rate_noise_radps * config_.yaw_rate_noise_radps;
  Eigen::Matrix<double, 1, 1> nu;
  Eigen::Matrix<double, 1, 1> s;
  // Not the chi-square gate of the poses: the gyro is inertial, blind to the field's
  // distortion that gate is for, and a turn that starts at once (3 rad/s from walking straight)
  // is far outside the filter's rate; gating it held the first tenth of a second of every sharp
  // corner back, the part the gyro is worn for. A rate no person turns at is refused.
  constexpr double kMaxPersonYawRateRadps = 10.0;  // a quick pivot on the spot is ~6
  if (std::abs(yaw_rate_radps) > kMaxPersonYawRateRadps) {
    ++counters_.rejected;
    return UpdateResult::kRejected;
  }
  (void)innovation_nis<1>(track_, rows, z, r, nu, s);
  apply_update<1>(track_, rows, nu, s, r);
  ++counters_.yaw_rate_updates;
  return UpdateResult::kAccepted;
}

HumanState human_state(const HumanTrack& track, Nanos t, const Pose2& base_in_odom,
                       const HumanEkfConfig& config, TrackerConfidence confidence) {
  HumanState h;
  h.confidence = confidence;
  if (!track.valid) return h;
  const HumanTrack p = predict_track(track, t, config);
  h.valid = true;
  h.pose_odom = Pose2{p.mean()(0), p.mean()(1), p.mean()(2)};
  h.velocity_odom = Point2{p.mean()(3), p.mean()(4)};
  h.yaw_rate_radps = p.mean()(5);
  const Pose2 odom_in_base = base_in_odom.inverse();
  h.pose_base = odom_in_base * h.pose_odom;
  h.velocity_base = odom_in_base.rotate(h.velocity_odom);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(p.covariance().topLeftCorner<2, 2>(),
                                                           Eigen::EigenvaluesOnly);
  h.position_sigma_m = std::sqrt(std::max(0.0, eig.eigenvalues()(1)));
  h.heading_sigma_rad = std::sqrt(std::max(0.0, p.covariance()(2, 2)));
  // Row-major copy (the track's storage is column-major).
  Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(h.pose_covariance_odom.data()) =
      p.covariance().topLeftCorner<3, 3>();

  h.age = t - track.last_update;
  return h;
}

}  // namespace core
