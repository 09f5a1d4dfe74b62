#include "core/control/mppi.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace core {
namespace {

constexpr size_t kPoolSize = size_t{1} << 20;

uint64_t next_random(uint64_t& s) {  // xorshift64*
  s ^= s >> 12;
  s ^= s << 25;
  s ^= s >> 27;
  return s * 2685821657736338717ULL;
}

bool finite(const Twist& t) {
  return std::isfinite(t.vx) && std::isfinite(t.vy) && std::isfinite(t.wz);
}

Twist clip(const Twist& u, const TwistLimits& l) {
  return Twist{std::clamp(u.vx, -l.vx, l.vx), std::clamp(u.vy, -l.vy, l.vy),
               std::clamp(u.wz, -l.wz, l.wz)};
}

}  // namespace

Mppi::Mppi(const MppiConfig& config)
    : cfg_(config),
      mean_(static_cast<size_t>(config.horizon_steps)),
      scratch_(mean_.size()),
      pool_(kPoolSize),
      offset_(static_cast<size_t>(config.samples)),
      cost_(offset_.size()),
      weight_(offset_.size()),
      rng_state_(config.seed * 0x9E3779B97F4A7C15ULL + 1) {
  person_frames_.reserve(static_cast<size_t>(config.horizon_steps) + 1);
  // Standard normals by Box-Muller from the seeded generator: same seed, same pool.
  for (size_t i = 0; i + 1 < pool_.size(); i += 2) {
    const double u1 = (static_cast<double>(next_random(rng_state_) >> 11) + 1.0) * 0x1.0p-53;
    const double u2 = static_cast<double>(next_random(rng_state_) >> 11) * 0x1.0p-53;
    const double r = std::sqrt(-2.0 * std::log(u1));
    pool_[i] = static_cast<float>(r * std::cos(2.0 * M_PI * u2));
    pool_[i + 1] = static_cast<float>(r * std::sin(2.0 * M_PI * u2));
  }
}

void Mppi::reset() {
  std::fill(mean_.begin(), mean_.end(), Twist{});
  has_time_ = false;
}

void Mppi::shift_mean(Nanos now) {
  if (!has_time_) {
    has_time_ = true;
    last_ = now;
    return;
  }
  const double steps = to_seconds(now - last_) / cfg_.step_s;
  last_ = now;
  if (steps <= 0) return;
  const size_t k_max = mean_.size();
  for (size_t k = 0; k < k_max; ++k) {
    const double pos = static_cast<double>(k) + steps;
    const auto i = static_cast<size_t>(pos);
    const double f = pos - static_cast<double>(i);
    const Twist& a = mean_[std::min(i, k_max - 1)];
    const Twist& b = mean_[std::min(i + 1, k_max - 1)];
    scratch_[k] =
        Twist{a.vx + f * (b.vx - a.vx), a.vy + f * (b.vy - a.vy), a.wz + f * (b.wz - a.wz)};
  }
  mean_.swap(scratch_);
}

double Mppi::rollout(size_t m, const MppiInputs& in) {
  // Hot loop (M x K per step): no trigonometry and no libm calls inside. The heading's cos/sin
  // advance by the rotation of w dt (a 5th-order series: |w dt| <= 0.2 rad, error < 3e-6), and
  // the person's predicted frames were prepared once per step (person_frames_).
  const size_t horizon = mean_.size();
  const double dt = cfg_.step_s;
  const Pose2& g = in.goal;
  const double cg = goal_cos_;
  const double sg = goal_sin_;
  const double two_pi = 2.0 * std::numbers::pi;
  auto tracking = [&](double x, double y, double th) {
    const double dx = x - g.x_m;
    const double dy = y - g.y_m;
    const double ex = cg * dx + sg * dy;
    const double ey = -sg * dx + cg * dy;
    double et = th - g.theta_rad;
    et -= two_pi * static_cast<double>(static_cast<int64_t>(et / two_pi + (et >= 0 ? 0.5 : -0.5)));
    return cfg_.q[0] * ex * ex + cfg_.q[1] * ey * ey + cfg_.q[2] * et * et;
  };
  const bool with_person = !person_frames_.empty();
  const double ia = 1.0 / (cfg_.ellipse.a_m * cfg_.ellipse.a_m);
  const double ib = 1.0 / (cfg_.ellipse.b_m * cfg_.ellipse.b_m);
  auto barrier_at = [&](size_t k, double x, double y) {
    const PersonFrame& f = person_frames_[std::min(k, person_frames_.size() - 1)];
    const double dx = x - f.x;
    const double dy = y - f.y;
    const double px = f.c * dx + f.s * dy;
    const double py = -f.s * dx + f.c * dy;
    return px * px * ia + py * py * ib - 1.0;
  };
  double x = in.robot.x_m, y = in.robot.y_m, th = in.robot.theta_rad;
  double c = robot_cos_;
  double s = robot_sin_;
  double h = with_person ? barrier_at(0, x, y) : 0.0;
  double cost = 0.0;
  size_t idx = offset_[m];
  Twist prev = in.current;
  const double dv = cfg_.linear_accel_mps2 * dt;
  const double dw = cfg_.angular_accel_radps2 * dt;
  const double inv_s0 = 1.0 / cfg_.sigma[0];
  const double inv_s1 = 1.0 / cfg_.sigma[1];
  const double inv_s2 = 1.0 / cfg_.sigma[2];
  for (size_t k = 0; k < horizon; ++k) {
    const Twist& mu = mean_[k];
    if (idx + 3 > kPoolSize) idx -= kPoolSize - 3;  // wrap (the pool is long; rare)
    const double n0 = pool_[idx];
    const double n1 = pool_[idx + 1];
    const double n2 = pool_[idx + 2];
    idx += 3;
    // The sampled control, within the velocity box and reachable from the previous one with the
    // base's accelerations (so the rollouts predict what the base will actually do).
    Twist u = clip(
        Twist{mu.vx + cfg_.sigma[0] * n0, mu.vy + cfg_.sigma[1] * n1, mu.wz + cfg_.sigma[2] * n2},
        cfg_.limits);
    u.vx = std::clamp(u.vx, prev.vx - dv, prev.vx + dv);
    u.vy = std::clamp(u.vy, prev.vy - dv, prev.vy + dv);
    u.wz = std::clamp(u.wz, prev.wz - dw, prev.wz + dw);
    prev = u;
    // lambda u^T Sigma^-1 eps, eps = sigma n: lambda sum(mu_d n_d / sigma_d)
    cost += cfg_.lambda * (mu.vx * n0 * inv_s0 + mu.vy * n1 * inv_s1 + mu.wz * n2 * inv_s2);
    x += (u.vx * c - u.vy * s) * dt;
    y += (u.vx * s + u.vy * c) * dt;
    const double a = u.wz * dt;
    const double a2 = a * a;
    const double ca = 1.0 - a2 / 2.0 + a2 * a2 / 24.0;
    const double sa = a * (1.0 - a2 / 6.0 + a2 * a2 / 120.0);
    const double c_next = c * ca - s * sa;
    s = s * ca + c * sa;
    c = c_next;
    th += a;
    cost += tracking(x, y, th);
    if (in.costmap != nullptr && in.costmap->cost(x, y) >= cfg_.cost_threshold) {
      cost += cfg_.collision_cost;
    }
    if (with_person) {
      const double h_next = barrier_at(k + 1, x, y);
      cost += cfg_.c_safe * std::max((1.0 - cfg_.dcbf_delta) * h - h_next, 0.0);
      h = h_next;
    }
  }
  cost += cfg_.terminal_weight * tracking(x, y, th);
  return cost;
}

MppiOutput Mppi::step(const MppiInputs& in) {
  MppiOutput out;
  const double elapsed = has_time_ ? std::clamp(to_seconds(in.now - last_), 1e-3, 0.2) : 0.01;
  shift_mean(in.now);
  // Per-step preparation shared by all samples.
  goal_cos_ = std::cos(in.goal.theta_rad);
  goal_sin_ = std::sin(in.goal.theta_rad);
  robot_cos_ = std::cos(in.robot.theta_rad);
  robot_sin_ = std::sin(in.robot.theta_rad);
  person_frames_.clear();
  for (size_t k = 0; k < in.person.size() && k < person_frames_.capacity(); ++k) {
    const Pose2& p = in.person[k];
    person_frames_.push_back({p.x_m, p.y_m, std::cos(p.theta_rad), std::sin(p.theta_rad)});
  }
  for (uint32_t& o : offset_) {
    o = static_cast<uint32_t>(next_random(rng_state_) % kPoolSize);
  }
  const auto samples = static_cast<int64_t>(offset_.size());
#pragma omp parallel for num_threads(cfg_.threads) schedule(static)
  for (int64_t m = 0; m < samples; ++m) {
    cost_[static_cast<size_t>(m)] = rollout(static_cast<size_t>(m), in);
  }
  double min_cost = std::numeric_limits<double>::infinity();
  for (const double c : cost_)
    min_cost = std::min(min_cost, c);
  double total = 0.0;
  for (size_t m = 0; m < cost_.size(); ++m) {
    weight_[m] = std::isfinite(cost_[m]) ? std::exp(-(cost_[m] - min_cost) / cfg_.lambda) : 0.0;
    total += weight_[m];
  }
  if (!std::isfinite(min_cost) || !(total > 0.0)) {
    reset();
    return out;  // ok = false, zero command
  }
  double sum_sq = 0.0;
  for (double& w : weight_) {
    w /= total;
    sum_sq += w * w;
  }
  // mean_k += sum_m w_m sigma n_{m,k}
  for (size_t k = 0; k < mean_.size(); ++k) {
    double d0 = 0, d1 = 0, d2 = 0;
    for (size_t m = 0; m < weight_.size(); ++m) {
      if (weight_[m] < 1e-12) continue;
      const size_t idx = offset_[m] + 3 * k;
      d0 += weight_[m] * static_cast<double>(pool_[idx % kPoolSize]);
      d1 += weight_[m] * static_cast<double>(pool_[(idx + 1) % kPoolSize]);
      d2 += weight_[m] * static_cast<double>(pool_[(idx + 2) % kPoolSize]);
    }
    Twist& mu = mean_[k];
    mu = clip(
        Twist{mu.vx + cfg_.sigma[0] * d0, mu.vy + cfg_.sigma[1] * d1, mu.wz + cfg_.sigma[2] * d2},
        cfg_.limits);
  }
  if (cfg_.smooth && mean_.size() >= 3) {
    scratch_ = mean_;
    for (size_t k = 1; k + 1 < mean_.size(); ++k) {
      mean_[k] =
          Twist{0.25 * scratch_[k - 1].vx + 0.5 * scratch_[k].vx + 0.25 * scratch_[k + 1].vx,
                0.25 * scratch_[k - 1].vy + 0.5 * scratch_[k].vy + 0.25 * scratch_[k + 1].vy,
                0.25 * scratch_[k - 1].wz + 0.5 * scratch_[k].wz + 0.25 * scratch_[k + 1].wz};
    }
  }
  out.nominal = mean_.front();
  out.min_cost = min_cost;
  out.effective_samples = 1.0 / sum_sq;
  Twist u = out.nominal;
  if (!in.person.empty()) {
    const Pose2& p0 = in.person.front();
    const Pose2& p1 = in.person.size() > 1 ? in.person[1] : in.person.front();
    const RepairResult r =
        repair(in.robot, p0, p1, u, cfg_.step_s, cfg_.dcbf_delta, cfg_.ellipse, cfg_.limits);
    u = r.u;
    out.repaired = r.modified;
    out.repair_feasible = r.feasible;
  }
  // Acceleration limits against the last command, over the time since the last step.
  const double dv = cfg_.linear_accel_mps2 * elapsed;
  const double dw = cfg_.angular_accel_radps2 * elapsed;
  u.vx = std::clamp(u.vx, in.current.vx - dv, in.current.vx + dv);
  u.vy = std::clamp(u.vy, in.current.vy - dv, in.current.vy + dv);
  u.wz = std::clamp(u.wz, in.current.wz - dw, in.current.wz + dw);
  u = clip(u, cfg_.limits);
  if (!finite(u)) {
    reset();
    return MppiOutput{};
  }
  out.command = u;
  out.ok = true;
  return out;
}

}  // namespace core
