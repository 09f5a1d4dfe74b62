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

// The plan's box: limits, with vx no lower than -reverse_speed_max_mps.
double plan_vx_min(const MppiConfig& c) {
  return -std::clamp(c.reverse_speed_max_mps, 0.0, c.limits.vx);
}

Twist clip_plan(const Twist& u, const MppiConfig& c) {
  Twist out = clip(u, c.limits);
  out.vx = std::max(out.vx, plan_vx_min(c));
  return out;
}

// How deep the segment from -> to runs into an ellipse (semi-axes a, b) centred at `centre` with
// heading (c, s): the least normalised radius on it (1 on the ellipse, 0 at its centre). In
// the ellipse's normalised frame the segment stays a segment and the ellipse a unit circle.
double chord_depth(Point2 centre, double c, double s, const Ellipse& e, Point2 from, Point2 to) {
  auto normalised = [&](Point2 p) {
    const double dx = p.x_m - centre.x_m;
    const double dy = p.y_m - centre.y_m;
    return Point2{(c * dx + s * dy) / e.a_m, (-s * dx + c * dy) / e.b_m};
  };
  const Point2 p = normalised(from);
  const Point2 q = normalised(to);
  const double ux = q.x_m - p.x_m;
  const double uy = q.y_m - p.y_m;
  const double length2 = ux * ux + uy * uy;
  const double t = length2 > 0 ? std::clamp(-(p.x_m * ux + p.y_m * uy) / length2, 0.0, 1.0) : 0.0;
  return std::hypot(p.x_m + t * ux, p.y_m + t * uy);
}

}  // namespace

Mppi::Mppi(const MppiConfig& config)
    : cfg_(config),
      mean_(static_cast<size_t>(config.horizon_steps)),
      scratch_(mean_.size()),
      update_(mean_.size()),
      pool_(kPoolSize),
      offset_((static_cast<size_t>(config.samples) + kLanes - 1) / kLanes +
              (config.guide_samples ? 1 : 0)),
      cost_(offset_.size() * kLanes),
      tracking_cost_(cost_.size()),
      collision_cost_(cost_.size()),
      barrier_cost_(cost_.size()),
      weight_(cost_.size()),
      obstacle_limit_(config.obstacle_speed),
      rng_state_(config.seed * 0x9E3779B97F4A7C15ULL + 1) {
  if (config.guide_samples) {
    guide_block_ = offset_.size() - 1;
    guide_noise_.resize(mean_.size() * 3 * kLanes);
  }
  person_frames_.reserve(static_cast<size_t>(config.horizon_steps) + 1);
  goal_frames_.reserve(static_cast<size_t>(config.horizon_steps) + 1);
  active_.reserve(weight_.size());
  // The path sample's buffers (a path is at most the cells its search expanded, plus its ends):
  // no allocation in the control loop.
  const auto most_points = static_cast<size_t>(std::max(config.path.max_expansions, 0)) + 3;
  path_.reserve(most_points);
  path_arc_.reserve(most_points);
  goal_arc_.reserve(static_cast<size_t>(config.horizon_steps) + 1);
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

// The 8 lanes of a block read 8 consecutive floats, so a block's rollout loads whole vectors
// (a pool block starts on a multiple of 8: its row never wraps round the pool's end).
const float* Mppi::noise_row(size_t block, size_t k, size_t d) const {
  if (block == guide_block_) return &guide_noise_[(k * 3 + d) * kLanes];
  return &pool_[(offset_[block] + (k * 3 + d) * kLanes) & (kPoolSize - 1)];
}

// The structured samples' controls, written as the noise that makes them (n = (u - mean) /
// sigma): lane 0 the mean, lane 1 a full brake, lanes 2 and 3 the steering law at full and half
// speed, lane 4 the path round an obstacle when one was planned (MppiConfig::path_guide), the
// rest random (the pool's, as any other block).
void Mppi::prepare_guide_block(const MppiInputs& in) {
  constexpr size_t kL = kLanes;
  const size_t horizon = mean_.size();
  const double dt = cfg_.step_s;
  const double dv = cfg_.linear_accel_mps2 * dt;
  const double dw = cfg_.angular_accel_radps2 * dt;
  const TwistLimits& lim = cfg_.limits;
  auto put = [&](size_t lane, size_t k, const Twist& u) {
    const Twist& mu = mean_[k];
    guide_noise_[(k * 3 + 0) * kL + lane] = static_cast<float>((u.vx - mu.vx) / cfg_.sigma[0]);
    guide_noise_[(k * 3 + 1) * kL + lane] = static_cast<float>((u.vy - mu.vy) / cfg_.sigma[1]);
    guide_noise_[(k * 3 + 2) * kL + lane] = static_cast<float>((u.wz - mu.wz) / cfg_.sigma[2]);
  };
  auto toward = [](double from, double to, double step) {
    return std::clamp(to, from - step, from + step);
  };
  // The steering law: the world velocity and turn rate of q^d's path plus a pull of 2/s toward
  // where q^d is at the same step (its heading's pull: guide_heading_gain_per_s), at most
  // `speed` of the box (scaled as a vector, so the direction holds); every step within the
  // base's accelerations, as the rollouts will clamp it. (Pulling toward q^d one step later ran
  // the law a step ahead of a walking person and its half-speed copy behind; the two tied ~5 cm
  // behind and took turns.) With a carrot (the path sample), the translation tracks the carrot's
  // path instead of q^d's.
  auto law = [&](size_t k, const Pose2& p, const Twist& prev, double speed, const Point2* carrot0,
                 const Point2* carrot1) {
    const TwistLimits box{lim.vx * speed, lim.vy * speed, lim.wz};
    const GoalFrame& g0 = goal_frames_[std::min(k, goal_frames_.size() - 1)];
    const GoalFrame& g1 = goal_frames_[std::min(k + 1, goal_frames_.size() - 1)];
    double wx = (g1.x - g0.x) / dt + 2.0 * (g0.x - p.x_m);
    double wy = (g1.y - g0.y) / dt + 2.0 * (g0.y - p.y_m);
    if (carrot0 != nullptr && carrot1 != nullptr) {
      wx = (carrot1->x_m - carrot0->x_m) / dt + 2.0 * (carrot0->x_m - p.x_m);
      wy = (carrot1->y_m - carrot0->y_m) / dt + 2.0 * (carrot0->y_m - p.y_m);
    }
    const double c = std::cos(p.theta_rad);
    const double s = std::sin(p.theta_rad);
    double bx = c * wx + s * wy;
    double by = -s * wx + c * wy;
    const double scale = std::min(
        {1.0, box.vx / std::max(std::abs(bx), 1e-9), box.vy / std::max(std::abs(by), 1e-9)});
    bx *= scale;
    by *= scale;
    const double bw =
        std::clamp(wrap_angle(g1.theta - g0.theta) / dt +
                       cfg_.guide_heading_gain_per_s * wrap_angle(g0.theta - p.theta_rad),
                   -box.wz, box.wz);
    return Twist{toward(prev.vx, bx, dv), toward(prev.vy, by, dv), toward(prev.wz, bw, dw)};
  };
  auto advance = [dt](const Pose2& p, const Twist& u) {
    const double c = std::cos(p.theta_rad);
    const double s = std::sin(p.theta_rad);
    return Pose2{p.x_m + (u.vx * c - u.vy * s) * dt, p.y_m + (u.vx * s + u.vy * c) * dt,
                 p.theta_rad + u.wz * dt};
  };
  auto steer = [&](size_t lane, double speed) {
    Pose2 p = in.robot;
    Twist prev = in.current;
    for (size_t k = 0; k < horizon; ++k) {
      const Twist u = law(k, p, prev, speed, nullptr, nullptr);
      put(lane, k, u);
      p = advance(p, u);
      prev = u;
    }
  };
  // The path sample: the steering law on a carrot that moves along the costmap path to q^d at
  // the horizon's end (q^d's own way runs through what the footprint would touch, or round an
  // obstacle the robot is on the wrong side of) at path_speed_mps, but never to where it would
  // have less left to go than q^d has: it waits for a q^d that is still to come, and reaches a
  // q^d that stands still.
  auto follow = [&](size_t lane) {
    Pose2 p = in.robot;
    Twist prev = in.current;
    const double length = path_arc_.back();
    const size_t last_goal = goal_frames_.size() - 1;
    const double goal_length = goal_arc_.back();
    size_t segment = 0;  // carrots only move forward along the path
    auto point_at = [&](double arc) {
      while (segment + 2 < path_arc_.size() && path_arc_[segment + 1] < arc)
        ++segment;
      const double span = path_arc_[segment + 1] - path_arc_[segment];
      const double f = span > 0 ? std::clamp((arc - path_arc_[segment]) / span, 0.0, 1.0) : 1.0;
      const Point2& a = path_[segment];
      const Point2& b = path_[segment + 1];
      return Point2{a.x_m + f * (b.x_m - a.x_m), a.y_m + f * (b.y_m - a.y_m)};
    };
    auto arc_at = [&](size_t k) {
      const double left = goal_length - goal_arc_[std::min(k, last_goal)];
      const double catching_up = cfg_.path_speed_mps * dt * static_cast<double>(k);
      return std::clamp(std::min(length - left, catching_up), 0.0, length);
    };
    Point2 carrot0 = point_at(arc_at(0));
    for (size_t k = 0; k < horizon; ++k) {
      const Point2 carrot1 = point_at(arc_at(k + 1));
      const Twist u = law(k, p, prev, 1.0, &carrot0, &carrot1);
      put(lane, k, u);
      p = advance(p, u);
      prev = u;
      carrot0 = carrot1;
    }
  };
  // The orbit sample: the steering law on a carrot that goes round the person from the robot's
  // bearing to q^d's, the way that does not pass in front of them (where a walking person goes:
  // the first version went either way, and round the front lost two random validation trials
  // in 80 to a person turning back), in the ellipse's normalised polar coordinates (rho 1 on
  // the barrier's ellipse) of the person's predicted frame at each step, so it walks with them:
  // out to orbit_radius, round at orbit_speed_mps, in to q^d over the last half radian.
  auto orbit = [&](size_t lane) {
    const double a = cfg_.ellipse.a_m;
    const double b = cfg_.ellipse.b_m;
    auto polar = [&](const PersonFrame& f, double x, double y, double& rho, double& phi) {
      const double dx = x - f.x;
      const double dy = y - f.y;
      const double lx = (f.c * dx + f.s * dy) / a;
      const double ly = (-f.s * dx + f.c * dy) / b;
      rho = std::hypot(lx, ly);
      phi = std::atan2(ly, lx);
    };
    double rho_robot = 0;
    double phi_robot = 0;
    polar(person_frames_.front(), in.robot.x_m, in.robot.y_m, rho_robot, phi_robot);
    double rho_goal0 = 0;
    double phi_goal0 = 0;
    polar(person_frames_.front(), goal_frames_.front().x, goal_frames_.front().y, rho_goal0,
          phi_goal0);
    // +1 counter-clockwise seen from above. On one side of the person: straight along it; from
    // one side to the other: round the back (through phi = pi).
    const bool robot_left = phi_robot >= 0.0;
    const double dir = robot_left == (phi_goal0 >= 0.0) ? (phi_goal0 >= phi_robot ? 1.0 : -1.0)
                       : robot_left                     ? 1.0
                                                        : -1.0;
    const double omega =
        cfg_.orbit_speed_mps / (cfg_.orbit_radius * std::sqrt(0.5 * (a * a + b * b)));
    constexpr double kLandingRad = 0.5;
    auto carrot_at = [&](size_t k) {
      const PersonFrame& f = person_frames_[std::min(k, person_frames_.size() - 1)];
      const GoalFrame& g = goal_frames_[std::min(k, goal_frames_.size() - 1)];
      double rho_goal = 0;
      double phi_goal = 0;
      polar(f, g.x, g.y, rho_goal, phi_goal);
      double to_go = wrap_angle(phi_goal - phi_robot);
      if (dir > 0 && to_go < 0) to_go += 2.0 * std::numbers::pi;
      if (dir < 0 && to_go > 0) to_go -= 2.0 * std::numbers::pi;
      const double travelled = std::min(omega * dt * static_cast<double>(k), std::abs(to_go));
      const double left = std::abs(to_go) - travelled;
      const double phi = phi_robot + dir * travelled;
      const double landing = std::clamp(left / kLandingRad, 0.0, 1.0);
      const double rho = rho_goal + (cfg_.orbit_radius - rho_goal) * landing;
      const double lx = rho * a * std::cos(phi);
      const double ly = rho * b * std::sin(phi);
      return Point2{f.x + f.c * lx - f.s * ly, f.y + f.s * lx + f.c * ly};
    };
    Pose2 p = in.robot;
    Twist prev = in.current;
    Point2 carrot0 = carrot_at(0);
    for (size_t k = 0; k < horizon; ++k) {
      const Point2 carrot1 = carrot_at(k + 1);
      const Twist u = law(k, p, prev, 1.0, &carrot0, &carrot1);
      put(lane, k, u);
      p = advance(p, u);
      prev = u;
      carrot0 = carrot1;
    }
  };
  Twist brake = in.current;
  for (size_t k = 0; k < horizon; ++k) {
    put(0, k, mean_[k]);
    brake = Twist{toward(brake.vx, 0.0, dv), toward(brake.vy, 0.0, dv), toward(brake.wz, 0.0, dw)};
    put(1, k, brake);
    for (size_t lane = 4; lane < kL; ++lane) {
      for (size_t d = 0; d < 3; ++d) {
        guide_noise_[(k * 3 + d) * kL + lane] =
            pool_[(offset_[guide_block_] + (k * 3 + d) * kL + lane) & (kPoolSize - 1)];
      }
    }
  }
  steer(2, 1.0);
  steer(3, 0.5);
  if (path_lane_ != kNoLane) follow(path_lane_);
  if (orbit_lane_ != kNoLane) orbit(orbit_lane_);
}

void Mppi::rollout_block(size_t block, const MppiInputs& in) {
  // Hot loop (M x K per step), 8 samples at a time in float, structure of arrays: no
  // trigonometry, no libm calls; the heading's cos/sin advance by the rotation of w dt (a
  // 5th-order series: |w dt| <= 0.2 rad, error < 3e-6); the person's predicted frames were
  // prepared once per step. The compiler vectorises the lane loops (SSE/AVX here, NEON on the
  // Jetson); the costmap lookup is a gather and stays scalar.
  constexpr size_t kL = kLanes;
  const size_t horizon = mean_.size();
  const auto dt = static_cast<float>(cfg_.step_s);
  const auto qx = static_cast<float>(cfg_.q[0]);
  const auto qy = static_cast<float>(cfg_.q[1]);
  const auto qt = static_cast<float>(cfg_.q[2]);
  const float two_pi = 6.283185307f;
  const float inv_two_pi = 1.0f / two_pi;
  const auto lvx = static_cast<float>(cfg_.limits.vx);
  const auto lvx_min = static_cast<float>(plan_vx_min(cfg_));
  const auto lvy = static_cast<float>(cfg_.limits.vy);
  const auto lwz = static_cast<float>(cfg_.limits.wz);
  const auto dv = static_cast<float>(cfg_.linear_accel_mps2 * cfg_.step_s);
  const auto dw = static_cast<float>(cfg_.angular_accel_radps2 * cfg_.step_s);
  const auto s0 = static_cast<float>(cfg_.sigma[0]);
  const auto s1 = static_cast<float>(cfg_.sigma[1]);
  const auto s2 = static_cast<float>(cfg_.sigma[2]);
  const auto lam = static_cast<float>(cfg_.lambda);
  const auto ia = static_cast<float>(1.0 / (cfg_.ellipse.a_m * cfg_.ellipse.a_m));
  const auto ib = static_cast<float>(1.0 / (cfg_.ellipse.b_m * cfg_.ellipse.b_m));
  const auto keep = static_cast<float>(1.0 - cfg_.dcbf_delta);
  const auto c_safe = static_cast<float>(cfg_.c_safe);
  const bool with_person = !person_frames_.empty();
  const bool with_map = in.costmap != nullptr;
  const auto collision = static_cast<float>(cfg_.collision_cost);
  const bool with_contact = cfg_.contact_cost > 0.0;
  const auto contact = static_cast<float>(cfg_.contact_cost);

  // Tracking: the error in the frame of the goal at step k (or of the robot at the start), the
  // angle wrapped to (-pi, pi].
  const bool robot_frame = cfg_.tracking_frame == TrackingFrame::kRobot;
  float gx = 0, gy = 0, gth = 0, cg = 1, sg = 0;
  auto goal_at = [&](size_t k) {
    const GoalFrame& g = goal_frames_[std::min(k, goal_frames_.size() - 1)];
    gx = static_cast<float>(g.x);
    gy = static_cast<float>(g.y);
    gth = static_cast<float>(g.theta);
    cg = static_cast<float>(robot_frame ? robot_cos_ : g.c);
    sg = static_cast<float>(robot_frame ? robot_sin_ : g.s);
  };
  auto tracking = [&](float px, float py, float pth) {
    const float dx = px - gx;
    const float dy = py - gy;
    const float ex = cg * dx + sg * dy;
    const float ey = -sg * dx + cg * dy;
    float et = pth - gth;
    const float turns = et * inv_two_pi;
    et -= two_pi * static_cast<float>(static_cast<int>(turns + (turns >= 0.0f ? 0.5f : -0.5f)));
    return qx * ex * ex + qy * ey * ey + qt * et * et;
  };
  alignas(32) float x[kL], y[kL], th[kL], c[kL], s[kL], pvx[kL], pvy[kL], pwz[kL], cost[kL], h[kL];
  alignas(32) float trk[kL], col[kL], bar[kL];  // the terms of cost, for diagnosis
  for (size_t j = 0; j < kL; ++j) {
    x[j] = static_cast<float>(in.robot.x_m);
    y[j] = static_cast<float>(in.robot.y_m);
    th[j] = static_cast<float>(in.robot.theta_rad);
    c[j] = static_cast<float>(robot_cos_);
    s[j] = static_cast<float>(robot_sin_);
    pvx[j] = static_cast<float>(in.current.vx);
    pvy[j] = static_cast<float>(in.current.vy);
    pwz[j] = static_cast<float>(in.current.wz);
    cost[j] = 0.0f;
    h[j] = 0.0f;
    trk[j] = 0.0f;
    col[j] = 0.0f;
    bar[j] = 0.0f;
  }
  auto barrier_lanes = [&](size_t k, float* out) {
    const PersonFrame& f = person_frames_[std::min(k, person_frames_.size() - 1)];
    const auto fx = static_cast<float>(f.x), fy = static_cast<float>(f.y);
    const auto fc = static_cast<float>(f.c), fs = static_cast<float>(f.s);
    for (size_t j = 0; j < kL; ++j) {
      const float dx = x[j] - fx;
      const float dy = y[j] - fy;
      const float px = fc * dx + fs * dy;
      const float py = -fs * dx + fc * dy;
      out[j] = px * px * ia + py * py * ib - 1.0f;
    }
  };
  if (with_person) barrier_lanes(0, h);
  alignas(32) float hn[kL];
  // The control cost's weight per lane: 0 for the structured samples (lanes 0-3 of the guide
  // block). lambda mu^T Sigma^-1 eps is the importance-sampling term of a random draw about the
  // mean; for a sample placed far from the mean on purpose it is no cost but an artefact of the
  // distance (the brake from 1.7 m/s earns about -3000 over the horizon) that would let it win
  // where it is worse.
  alignas(32) float control_weight[kL];
  for (size_t j = 0; j < kL; ++j)
    control_weight[j] = block == guide_block_ && j < structured_lanes_ ? 0.0f : 1.0f;
  for (size_t k = 0; k < horizon; ++k) {
    const auto mvx = static_cast<float>(mean_[k].vx);
    const auto mvy = static_cast<float>(mean_[k].vy);
    const auto mwz = static_cast<float>(mean_[k].wz);
    const float* n0 = noise_row(block, k, 0);
    const float* n1 = noise_row(block, k, 1);
    const float* n2 = noise_row(block, k, 2);
    goal_at(k + 1);  // the control of step k leads to the state of step k + 1
    for (size_t j = 0; j < kL; ++j) {
      // The sampled control, in the velocity box and reachable from the previous one with the
      // base's accelerations (so the rollouts predict what the base will actually do).
      float vx = std::clamp(mvx + s0 * n0[j], lvx_min, lvx);
      float vy = std::clamp(mvy + s1 * n1[j], -lvy, lvy);
      float wz = std::clamp(mwz + s2 * n2[j], -lwz, lwz);
      vx = std::clamp(vx, pvx[j] - dv, pvx[j] + dv);
      vy = std::clamp(vy, pvy[j] - dv, pvy[j] + dv);
      wz = std::clamp(wz, pwz[j] - dw, pwz[j] + dw);
      pvx[j] = vx;
      pvy[j] = vy;
      pwz[j] = wz;
      // lambda u^T Sigma^-1 eps, eps = sigma n: lambda sum(mu_d n_d / sigma_d)
      cost[j] += control_weight[j] * lam * (mvx * n0[j] / s0 + mvy * n1[j] / s1 + mwz * n2[j] / s2);
      x[j] += (vx * c[j] - vy * s[j]) * dt;
      y[j] += (vx * s[j] + vy * c[j]) * dt;
      const float a = wz * dt;
      const float a2 = a * a;
      const float ca = 1.0f - a2 * 0.5f + a2 * a2 * (1.0f / 24.0f);
      const float sa = a * (1.0f - a2 * (1.0f / 6.0f) + a2 * a2 * (1.0f / 120.0f));
      const float cn = c[j] * ca - s[j] * sa;
      s[j] = s[j] * ca + c[j] * sa;
      c[j] = cn;
      th[j] += a;
      const float track = tracking(x[j], y[j], th[j]);
      cost[j] += track;
      trk[j] += track;
    }
    if (with_map) {
      for (size_t j = 0; j < kL; ++j) {
        if (in.costmap->cost_at_least(x[j], y[j], cfg_.cost_threshold)) {
          const float c_step =
              with_contact && in.costmap->cost_at_least(x[j], y[j], cfg_.contact_threshold)
                  ? contact
                  : collision;
          cost[j] += c_step;
          col[j] += c_step;
        }
      }
    }
    if (with_person) {
      barrier_lanes(k + 1, hn);
      for (size_t j = 0; j < kL; ++j) {
        const float barrier = c_safe * std::max(keep * h[j] - hn[j], 0.0f);
        cost[j] += barrier;
        bar[j] += barrier;
        h[j] = hn[j];
      }
    }
  }
  const auto tw = static_cast<float>(cfg_.terminal_weight);
  goal_at(horizon);
  for (size_t j = 0; j < kL; ++j) {
    const size_t m = block * kL + j;
    // The total as one running sum (the terms are kept beside it, not summed into it).
    const float terminal = tw * tracking(x[j], y[j], th[j]);
    cost_[m] = static_cast<double>(cost[j] + terminal);
    tracking_cost_[m] = trk[j] + terminal;
    collision_cost_[m] = col[j];
    barrier_cost_[m] = bar[j];
  }
}

MppiOutput Mppi::step(const MppiInputs& in) {
  MppiOutput out;
  const double elapsed = has_time_ ? std::clamp(to_seconds(in.now - last_), 1e-3, 0.2) : 0.01;
  shift_mean(in.now);
  // Per-step preparation shared by all samples.
  goal_frames_.clear();
  if (in.goal_path.empty()) {
    goal_frames_.push_back({in.goal.x_m, in.goal.y_m, in.goal.theta_rad,
                            std::cos(in.goal.theta_rad), std::sin(in.goal.theta_rad)});
  }
  for (size_t k = 0; k < in.goal_path.size() && k < goal_frames_.capacity(); ++k) {
    const Pose2& g = in.goal_path[k];
    const double heading = k < in.goal_heading_path.size() ? in.goal_heading_path[k] : g.theta_rad;
    goal_frames_.push_back({g.x_m, g.y_m, heading, std::cos(g.theta_rad), std::sin(g.theta_rad)});
  }
  robot_cos_ = std::cos(in.robot.theta_rad);
  robot_sin_ = std::sin(in.robot.theta_rad);
  person_frames_.clear();
  for (size_t k = 0; k < in.person.size() && k < person_frames_.capacity(); ++k) {
    const Pose2& p = in.person[k];
    person_frames_.push_back({p.x_m, p.y_m, std::cos(p.theta_rad), std::sin(p.theta_rad)});
  }
  for (uint32_t& o : offset_) {
    // A block's noise is contiguous per (step, dimension): aligned to whole vectors.
    o = static_cast<uint32_t>(next_random(rng_state_) % kPoolSize) & ~uint32_t{kLanes - 1};
  }
  structured_lanes_ = 4;
  path_lane_ = kNoLane;
  orbit_lane_ = kNoLane;
  path_.clear();
  if (guide_block_ != SIZE_MAX && cfg_.path_guide && in.costmap != nullptr) {
    // Cells where the footprint would touch (the contact tier's), or the lethal core without
    // it, on the robot's straight line to q^d now or on q^d's own way over the horizon (every
    // second): the steering law would run through them. The path goes round, to q^d at the end.
    CostmapPathConfig path_config = cfg_.path;
    path_config.unsafe_cost = cfg_.cost_threshold;
    if (cfg_.contact_cost > 0.0) {
      path_config.blocked_cost = std::min(path_config.blocked_cost, cfg_.contact_threshold);
    }
    const Point2 from{in.robot.x_m, in.robot.y_m};
    Point2 previous = from;
    bool blocked = false;
    const size_t last_goal = goal_frames_.size() - 1;
    for (size_t k = 0; !blocked; k += 10) {
      const GoalFrame& g = goal_frames_[std::min(k, last_goal)];
      const Point2 next{g.x, g.y};
      blocked = segment_crosses(*in.costmap, previous, next, path_config.blocked_cost);
      previous = next;
      if (k >= last_goal) break;
    }
    // The path keeps out of the unsafe band (cost >= R) where it can, so that the law following
    // it with some error stays clear of the contact tier too; through the band only where
    // nothing else leads there (a gap the band closes).
    const GoalFrame& end = goal_frames_.back();
    auto plan_below = [&](double cost) {
      CostmapPathConfig c = path_config;
      c.blocked_cost = cost;
      return planner_.plan(from, {end.x, end.y}, c, path_) == CostmapPathResult::kFound;
    };
    if (blocked) planner_.set_map(*in.costmap, cfg_.path_cell_m);
    if (blocked &&
        (plan_below(cfg_.cost_threshold) || (path_config.blocked_cost > cfg_.cost_threshold &&
                                             plan_below(path_config.blocked_cost)))) {
      path_arc_.assign(1, 0.0);
      for (size_t i = 1; i < path_.size(); ++i) {
        path_arc_.push_back(path_arc_.back() + std::hypot(path_[i].x_m - path_[i - 1].x_m,
                                                          path_[i].y_m - path_[i - 1].y_m));
      }
      goal_arc_.assign(1, 0.0);
      for (size_t k = 1; k < goal_frames_.size(); ++k) {
        goal_arc_.push_back(goal_arc_.back() +
                            std::hypot(goal_frames_[k].x - goal_frames_[k - 1].x,
                                       goal_frames_[k].y - goal_frames_[k - 1].y));
      }
      path_lane_ = structured_lanes_++;
      out.path_planned = true;
    }
  }
  if (guide_block_ != SIZE_MAX && cfg_.orbit_guide && !person_frames_.empty() &&
      chord_depth({person_frames_.front().x, person_frames_.front().y}, person_frames_.front().c,
                  person_frames_.front().s, cfg_.ellipse, {in.robot.x_m, in.robot.y_m},
                  {goal_frames_.front().x, goal_frames_.front().y}) < cfg_.orbit_trigger_radius) {
    orbit_lane_ = structured_lanes_++;
    out.orbit_planned = true;
  }
  if (guide_block_ != SIZE_MAX) prepare_guide_block(in);
  const auto blocks = static_cast<int64_t>(offset_.size());
#pragma omp parallel for num_threads(cfg_.threads) schedule(static)
  for (int64_t b = 0; b < blocks; ++b)
    rollout_block(static_cast<size_t>(b), in);
  // The structured samples (lanes 0-3 of the guide block) do not enter the weighted average:
  // they lie far from the mean on purpose, and any weight they had would pull it toward them
  // step after step (the brake toward a standstill) whether or not they were better. One of them
  // replaces the plan instead, when it beats every random sample.
  auto structured = [&](size_t m) {
    return m / kLanes == guide_block_ && m % kLanes < structured_lanes_;
  };
  double min_cost = std::numeric_limits<double>::infinity();
  size_t best = 0;
  double guide_cost = std::numeric_limits<double>::infinity();
  size_t guide = 0;
  for (size_t m = 0; m < cost_.size(); ++m) {
    if (structured(m)) {
      if (m % kLanes != 0 && cost_[m] < guide_cost) {  // lane 0, the mean itself, is no change
        guide_cost = cost_[m];
        guide = m;
      }
    } else if (cost_[m] < min_cost) {
      min_cost = cost_[m];
      best = m;
    }
  }
  if (!std::isfinite(min_cost)) {
    reset();
    return out;  // ok = false, zero command
  }
  const bool take_guide = guide_cost < min_cost;
  out.guided = take_guide;
  const size_t guide_lane = guide % kLanes;
  out.path_guided = take_guide && guide_lane == path_lane_;
  out.orbit_guided = take_guide && guide_lane == orbit_lane_;
  if (take_guide) best = guide;
  out.best.tracking = static_cast<double>(tracking_cost_[best]);
  out.best.collision = static_cast<double>(collision_cost_[best]);
  out.best.barrier = static_cast<double>(barrier_cost_[best]);
  out.best.control = cost_[best] - out.best.tracking - out.best.collision - out.best.barrier;
  // Importance weights at temperature lambda; raised (geometrically, then bisected in log space)
  // when fewer than min_effective_samples samples would carry the update.
  auto weigh = [&](double lambda) {
    double total = 0.0;
    for (size_t m = 0; m < cost_.size(); ++m) {
      weight_[m] = std::isfinite(cost_[m]) && !structured(m)
                       ? std::exp(-(cost_[m] - min_cost) / lambda)
                       : 0.0;
      total += weight_[m];
    }
    double sum_sq = 0.0;
    for (double& w : weight_) {
      w /= total;
      sum_sq += w * w;
    }
    return 1.0 / sum_sq;  // total >= 1: the best sample weighs exp(0)
  };
  double lambda = cfg_.lambda;
  double ess = weigh(lambda);
  const auto want = static_cast<double>(
      std::min<size_t>(static_cast<size_t>(std::max(cfg_.min_effective_samples, 0)), cost_.size()));
  if (ess < want) {
    double lo = lambda;
    double hi = lambda;
    for (int i = 0; i < 40 && weigh(hi) < want; ++i) {
      lo = hi;
      hi *= 4.0;
    }
    // Five halvings of the log-bracket: lambda within 4^(1/32) = 4.4 % of the least that gives
    // the floor (the upper end is kept, so the floor always holds).
    for (int i = 0; i < 5; ++i) {
      const double mid = std::sqrt(lo * hi);
      (weigh(mid) < want ? lo : hi) = mid;
    }
    lambda = hi;
    ess = weigh(lambda);
  }
  if (!std::isfinite(ess)) {
    reset();
    return out;
  }
  // mean_k += sum_m w_m sigma n_{m,k}, over the samples that carry weight (a handful at
  // lambda = 1 with costs in the thousands; some hundreds with the effective-sample floor).
  active_.clear();
  for (size_t m = 0; m < weight_.size(); ++m) {
    // Below 1e-6 a sample moves the mean by less than 1e-6 sigma: skipped (at most 0.2 % of
    // the total weight with M = 2000).
    if (weight_[m] >= 1e-6) active_.push_back(static_cast<uint32_t>(m));
  }
  // Sample by sample (each sample's noise lies in one small stretch of the pool, so it is read
  // from cache; step by step it was a cache miss per sample), the sums still in ascending m.
  std::fill(update_.begin(), update_.end(), Twist{});
  if (take_guide) active_.assign(1, static_cast<uint32_t>(guide));  // the whole way, weight 1
  for (const uint32_t m : active_) {
    const double w = take_guide ? 1.0 : weight_[m];
    const size_t block = m / kLanes;
    const size_t lane = m % kLanes;
    for (size_t k = 0; k < mean_.size(); ++k) {
      Twist& d = update_[k];
      d.vx += w * static_cast<double>(noise_row(block, k, 0)[lane]);
      d.vy += w * static_cast<double>(noise_row(block, k, 1)[lane]);
      d.wz += w * static_cast<double>(noise_row(block, k, 2)[lane]);
    }
  }
  for (size_t k = 0; k < mean_.size(); ++k) {
    const Twist& d = update_[k];
    Twist& mu = mean_[k];
    mu = clip_plan(Twist{mu.vx + cfg_.sigma[0] * d.vx, mu.vy + cfg_.sigma[1] * d.vy,
                         mu.wz + cfg_.sigma[2] * d.wz},
                   cfg_);
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
  out.min_cost = cost_[best];
  out.effective_samples = ess;
  out.lambda = lambda;
  Twist u = out.nominal;
  if (!in.person.empty()) {
    const Pose2& p0 = in.person.front();
    const Pose2& p1 = in.person.size() > 1 ? in.person[1] : in.person.front();
    const RepairResult r =
        repair(in.robot, p0, p1, u, cfg_.step_s, cfg_.dcbf_delta, cfg_.ellipse, cfg_.limits);
    u = r.u;
    out.repaired = r.modified;
    out.repair_feasible = r.feasible;
    if (cfg_.closing.robot_decel_mps2 > 0.0) {
      // The person's position and velocity in base_link (the velocity of the prediction's
      // first step: the filter's).
      const Pose2 odom_in_base = in.robot.inverse();
      const Point2 person = odom_in_base.apply({p0.x_m, p0.y_m});
      const Point2 velocity =
          odom_in_base.rotate({(p1.x_m - p0.x_m) / cfg_.step_s, (p1.y_m - p0.y_m) / cfg_.step_s});
      const ClosingSpeedResult c =
          limit_closing_speed(person, velocity, u, cfg_.closing, cfg_.limits);
      u = c.u;
      out.closing_limited = c.limited;
    }
  }
  if (in.costmap != nullptr) {
    const ObstacleSpeedResult o = obstacle_limit_.apply(*in.costmap, in.robot, u);
    u = o.u;
    out.obstacle_limited = o.limited;
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
