#include "sim/sim_world.hpp"

#include <fcntl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <numbers>

#include "hal/serial_port.hpp"

namespace sim {

namespace {
// The daemon's end of the lidar queue (the world keeps pushing into it).
class SharedDatagramSource final : public hal::DatagramSource {
 public:
  explicit SharedDatagramSource(std::shared_ptr<hal::DatagramQueue> q) : q_(std::move(q)) {}
  size_t drain(size_t max, hal::Nanos now,
               const std::function<void(const hal::UdpDatagram&)>& on) override {
    return q_->drain(max, now, on);
  }
  [[nodiscard]] hal::UdpStats stats() const override { return q_->stats(); }

 private:
  std::shared_ptr<hal::DatagramQueue> q_;
};

std::string next_network_name() {
  static std::atomic<uint64_t> n{0};
  return "simworld-" + std::to_string(n.fetch_add(1));
}

constexpr double kReplayedRadiusM = 0.25;  // recorded people: body radius

// Distance from a point to an axis-aligned box (0 inside).
double box_distance(double x, double y, double x0, double x1, double y0, double y1) {
  const double dx = std::max({x0 - x, 0.0, x - x1});
  const double dy = std::max({y0 - y, 0.0, y - y1});
  return std::hypot(dx, dy);
}
}  // namespace

SimWorld::SimWorld(Scenario scenario, const SimWorldConfig& config, hal::Clock& clock)
    : scenario_(std::move(scenario)),
      config_(config),
      clock_(clock),
      can_network_(next_network_name()),
      base_bus_(std::make_unique<hal::VirtualCanBus>(can_network_, clock)),
      daemon_bus_(std::make_unique<hal::VirtualCanBus>(can_network_, clock)),
      base_(std::make_unique<SimScoutMini>(*base_bus_, config.base)),
      tracker_(config.tracker),
      lidar_(config.lidar),
      lidar_queue_(std::make_shared<hal::DatagramQueue>()),
      r_base_source_(amfitrack::rotation_rpy(config.tracker_extrinsics.source_rpy_rad)),
      t_base_source_(config.tracker_extrinsics.source_xyz_m[0],
                     config.tracker_extrinsics.source_xyz_m[1],
                     config.tracker_extrinsics.source_xyz_m[2]),
      r_body_sensor_(amfitrack::rotation_rpy(config.tracker_extrinsics.sensor_in_body_rpy_rad)) {
  for (const Pedestrian& p : scenario_.pedestrians)
    crowd_.add(p);
  person_ = scenario_.person.pose_at(0.0);
  replayed_.resize(scenario_.replayed.size());
  prev_robot_ = scenario_.robot_start;
}

SimWorld::~SimWorld() {
  if (tracker_fd_ >= 0) ::close(tracker_fd_);
}

std::unique_ptr<hal::CanBus> SimWorld::take_base_bus() {
  return std::move(daemon_bus_);
}

std::unique_ptr<hal::VirtualCanBus> SimWorld::open_can_sniffer() {
  return std::make_unique<hal::VirtualCanBus>(can_network_, clock_);
}

std::unique_ptr<amfitrack::PacketLink> SimWorld::take_tracker_link() {
  std::array<int, 2> fds{-1, -1};
  if (tracker_fd_ >= 0 || ::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, fds.data()) != 0) {
    return nullptr;
  }
  tracker_fd_ = fds[0];
  (void)::fcntl(tracker_fd_, F_SETFL, ::fcntl(tracker_fd_, F_GETFL) | O_NONBLOCK);
  return std::make_unique<amfitrack::SerialCobsLink>(hal::adopt_serial_fd(fds[1]));
}

std::unique_ptr<hal::DatagramSource> SimWorld::take_lidar_source() {
  return std::make_unique<SharedDatagramSource>(lidar_queue_);
}

core::Pose2 SimWorld::robot_pose() const {
  const auto& p = base_->pose();
  return scenario_.robot_start * core::Pose2{p.x_m, p.y_m, p.theta_rad};
}

std::vector<Point2> SimWorld::pedestrian_positions() const {
  std::vector<Point2> out;
  for (const Pedestrian& p : crowd_.people())
    out.push_back(p.position);
  for (const auto& w : replayed_) {
    if (w) out.push_back(w->at);
  }
  return out;
}

core::Pose2 SimWorld::robot_at(hal::Nanos t) const {
  const core::Pose2 now = robot_pose();
  if (last_step_ <= prev_robot_time_) return now;
  const double s = std::clamp(static_cast<double>((t - prev_robot_time_).count()) /
                                  static_cast<double>((last_step_ - prev_robot_time_).count()),
                              0.0, 1.0);
  return core::interpolate(prev_robot_, now, s);
}

void SimWorld::move_person(double t_s, double dt_s) {
  const core::Pose2 scripted = scenario_.person.pose_at(t_s);
  if (!config_.person_avoids_robot || dt_s <= 0) {
    person_ = scripted;
    person_offset_ = {};
    person_velocity_ = scenario_.person.velocity_at(t_s);
    return;
  }
  const ScriptedWalker w =
      step_clear_of_robot({{person_.x_m, person_.y_m}, person_offset_, person_velocity_}, scripted,
                          scenario_.person_radius_m, dt_s);
  person_offset_ = w.offset;
  person_velocity_ = w.velocity;
  person_ = {w.at.x_m, w.at.y_m, scripted.theta_rad};
}

void SimWorld::move_replayed(double t_s, double dt_s) {
  for (size_t i = 0; i < scenario_.replayed.size(); ++i) {
    const Trajectory& r = scenario_.replayed[i];
    std::optional<ScriptedWalker>& w = replayed_[i];
    if (t_s < r.start_s() || t_s > r.end_s()) {
      w.reset();
      continue;
    }
    const core::Pose2 scripted = r.pose_at(t_s);
    const bool appears = !w.has_value();
    if (appears || !config_.replayed_avoid_robot || dt_s <= 0) {
      w = ScriptedWalker{{scripted.x_m, scripted.y_m}, {}, r.velocity_at(t_s)};
      if (appears && config_.replayed_avoid_robot) w->at = clear_of_robot(w->at, kReplayedRadiusM);
      w->offset = {w->at.x_m - scripted.x_m, w->at.y_m - scripted.y_m};
      continue;
    }
    w = step_clear_of_robot(*w, scripted, kReplayedRadiusM, dt_s);
  }
}

Point2 SimWorld::footprint_normal(const Point2& p) const {
  const core::Pose2 robot = robot_pose();
  const Point2 q = robot.inverse().apply(p);
  const Point2 c{std::clamp(q.x_m, config_.footprint_x_min_m, config_.footprint_x_max_m),
                 std::clamp(q.y_m, config_.footprint_y_min_m, config_.footprint_y_max_m)};
  double nx = q.x_m - c.x_m, ny = q.y_m - c.y_m;
  double n_len = std::hypot(nx, ny);
  if (n_len < 1e-9) {  // inside (the robot drove into them, or they appeared there): outward
    nx = q.x_m;
    ny = q.y_m;
    n_len = std::max(std::hypot(nx, ny), 1e-9);
  }
  return robot.rotate({nx / n_len, ny / n_len});
}

Point2 SimWorld::clear_of_robot(Point2 p, double radius_m) const {
  // In centimetre steps along the normal: it runs only when someone appears at the robot.
  constexpr double kStepM = 0.01;
  constexpr int kMaxSteps = 300;
  const Point2 n = footprint_normal(p);
  for (int i = 0;
       i < kMaxSteps && footprint_distance(p) - radius_m < config_.person_contact_margin_m; ++i) {
    p = {p.x_m + kStepM * n.x_m, p.y_m + kStepM * n.y_m};
  }
  return p;
}

SimWorld::ScriptedWalker SimWorld::step_clear_of_robot(const ScriptedWalker& w,
                                                       const core::Pose2& scripted, double radius_m,
                                                       double dt_s) const {
  const Point2 from = w.at;
  // Back toward the path, at most person_return_mps.
  Point2 offset = w.offset;
  const double off_m = std::hypot(offset.x_m, offset.y_m);
  if (off_m > 0) {
    const double keep = std::max(off_m - config_.person_return_mps * dt_s, 0.0) / off_m;
    offset = {offset.x_m * keep, offset.y_m * keep};
  }
  Point2 to{scripted.x_m + offset.x_m, scripted.y_m + offset.y_m};
  const double margin = config_.person_contact_margin_m;
  const double gap_from = footprint_distance(from) - radius_m;
  const double gap_to = footprint_distance(to) - radius_m;
  if (gap_to < margin && gap_to < gap_from) {
    const core::Pose2 robot = robot_pose();
    const Point2 n = footprint_normal(from);
    Point2 step{to.x_m - from.x_m, to.y_m - from.y_m};
    const double into = step.x_m * n.x_m + step.y_m * n.y_m;
    if (into < 0) {
      // Around the robot along its side, the way they walk (their heading, not the step: their
      // path pulls them back toward the robot's middle, and they would dither in front of it);
      // facing a side square on, past the side of its centre they are on (their right when
      // straight at it); at least at 0.7 of their pace.
      const Point2 heading{std::cos(scripted.theta_rad), std::sin(scripted.theta_rad)};
      Point2 t{-n.y_m, n.x_m};
      const double forward = t.x_m * heading.x_m + t.y_m * heading.y_m;
      const double left_of_centre =
          heading.x_m * (from.y_m - robot.y_m) - heading.y_m * (from.x_m - robot.x_m);
      constexpr double kSquareOn = 0.05;  // |cos| of the side to the heading
      const double t_left = -t.x_m * heading.y_m + t.y_m * heading.x_m;  // t . (their left)
      const bool flip =
          std::abs(forward) > kSquareOn ? forward < 0 : (left_of_centre > 1e-9) != (t_left > 0);
      if (flip) t = {-t.x_m, -t.y_m};
      const double len = std::hypot(step.x_m, step.y_m);
      const double along = std::max(step.x_m * t.x_m + step.y_m * t.y_m, 0.7 * len);
      step = {along * t.x_m, along * t.y_m};
    }
    to = {from.x_m + step.x_m, from.y_m + step.y_m};
    // Nor into a wall while sliding, nor closer to the robot than they were.
    const double wall_to = scenario_.world.distance(to);
    constexpr double kSlideToleranceM = 1e-6;  // sliding along a side keeps the gap, to rounding
    if (footprint_distance(to) - radius_m < std::min(margin, gap_from) - kSlideToleranceM ||
        (wall_to < radius_m && wall_to < scenario_.world.distance(from))) {
      to = from;
    }
  }
  return {to,
          {to.x_m - scripted.x_m, to.y_m - scripted.y_m},
          {(to.x_m - from.x_m) / dt_s, (to.y_m - from.y_m) / dt_s}};
}

void SimWorld::advance(double t_s) {
  const double dt = t_s - t_s_;
  move_person(t_s, dt);
  if (dt > 0) {
    sway_phase_rad_ =
        std::fmod(sway_phase_rad_ + sway_phase_rate_radps() * dt, 2.0 * std::numbers::pi);
  }
  move_replayed(t_s, dt);
  if (dt > 0) {
    const core::Pose2 robot = robot_pose();
    const auto& v = base_->velocity();
    const Point2 v_world = robot.rotate({v.vx_mps, v.vy_mps});
    bodies_.clear();
    bodies_.push_back({{person_.x_m, person_.y_m}, person_velocity_, scenario_.person_radius_m});
    bodies_.push_back({{robot.x_m, robot.y_m}, v_world, config_.robot_avoid_radius_m});
    for (const auto& w : replayed_) {
      if (w) bodies_.push_back({w->at, w->velocity, kReplayedRadiusM});
    }
    crowd_.step(dt, scenario_.world, bodies_);
  }
  t_s_ = t_s;
}

double SimWorld::sway_phase_rate_radps() const {
  return 2.0 * std::numbers::pi * std::hypot(person_velocity_.x_m, person_velocity_.y_m) /
         config_.person_stride_m;
}

void SimWorld::update_tracker_pose() {
  // The person in base_link, then in the source's frame: what the sensor reports.
  const core::Pose2 rel = robot_pose().inverse() * person_;
  const Eigen::Vector3d p_base(rel.x_m, rel.y_m, config_.sensor_height_m);
  const Eigen::Vector3d p_source = r_base_source_.transpose() * (p_base - t_base_source_);
  const double sway_rad = config_.person_sway_rad * std::sin(sway_phase_rad_);
  const Eigen::Matrix3d r_base_body =
      Eigen::AngleAxisd(rel.theta_rad + sway_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Quaterniond q(r_base_source_.transpose() * r_base_body * r_body_sensor_);
  tracker_.set_sensor_pose({p_source.x(), p_source.y(), p_source.z()},
                           {q.x(), q.y(), q.z(), q.w()});
  // The gyro: the torso turns about the vertical at the walking heading's rate plus the sway's,
  // whatever the robot does (a gyro is inertial); in the sensor's own axes.
  const double body_rate_radps =
      scenario_.person.turn_rate_at(t_s_) +
      config_.person_sway_rad * std::cos(sway_phase_rad_) * sway_phase_rate_radps();
  const Eigen::Vector3d gyro_dps =
      r_body_sensor_.transpose() *
      Eigen::Vector3d(0, 0, body_rate_radps * 180.0 / std::numbers::pi);
  tracker_.set_gyro_dps({gyro_dps.x(), gyro_dps.y(), gyro_dps.z()});
}

void SimWorld::step(hal::Nanos now) {
  if (!started_) {
    started_ = true;
    last_step_ = now;
    prev_robot_time_ = now;
    advance(0.0);
  }
  const hal::Nanos step(static_cast<int64_t>(config_.step_s * 1e9));
  while (last_step_ + step <= now) {
    prev_robot_ = robot_pose();
    prev_robot_time_ = last_step_;
    last_step_ += step;
    advance(t_s_ + config_.step_s);
    base_->step(last_step_);
    update_tracker_pose();
    tracker_.step(last_step_);
    if (tracker_fd_ >= 0) (void)tracker_.pump_cobs(tracker_fd_);
    cylinders_.clear();
    cylinders_.push_back({{person_.x_m, person_.y_m}, scenario_.person_radius_m, 1.75});
    for (const Pedestrian& p : crowd_.people())
      cylinders_.push_back({p.position, p.radius_m, 1.75});
    for (const auto& w : replayed_) {
      if (w) cylinders_.push_back({w->at, kReplayedRadiusM, 1.75});
    }
    lidar_.step(
        last_step_, scenario_.world, cylinders_, [this](hal::Nanos t) { return robot_at(t); },
        [this](std::span<const uint8_t> bytes, hal::Nanos arrival) {
          if (!lidar_silent_) lidar_queue_->push(bytes, arrival);
        });
  }
}

double SimWorld::footprint_distance(const Point2& p) const {
  const core::Point2 q = robot_pose().inverse().apply(p);
  return box_distance(q.x_m, q.y_m, config_.footprint_x_min_m, config_.footprint_x_max_m,
                      config_.footprint_y_min_m, config_.footprint_y_max_m);
}

double SimWorld::footprint_clearance_static() const {
  // Exact box-to-segment and box-to-circle distances in base_link.
  const core::Pose2 inv = robot_pose().inverse();
  const double x0 = config_.footprint_x_min_m, x1 = config_.footprint_x_max_m;
  const double y0 = config_.footprint_y_min_m, y1 = config_.footprint_y_max_m;
  const std::array<Point2, 4> corners{Point2{x0, y0}, Point2{x1, y0}, Point2{x1, y1},
                                      Point2{x0, y1}};
  double best = std::numeric_limits<double>::infinity();
  for (const Segment& w : scenario_.world.segments) {
    const Segment s{inv.apply(w.a), inv.apply(w.b)};
    // A segment that crosses the box (Liang-Barsky clip leaves a piece) touches it.
    double t0 = 0, t1 = 1;
    const double dx = s.b.x_m - s.a.x_m, dy = s.b.y_m - s.a.y_m;
    bool inside = true;
    for (const auto& [p, q] : std::array<std::pair<double, double>, 4>{
             {{-dx, s.a.x_m - x0}, {dx, x1 - s.a.x_m}, {-dy, s.a.y_m - y0}, {dy, y1 - s.a.y_m}}}) {
      if (p == 0) {
        if (q < 0) inside = false;
      } else {
        const double r = q / p;
        if (p < 0) {
          t0 = std::max(t0, r);
        } else {
          t1 = std::min(t1, r);
        }
      }
    }
    if (inside && t0 <= t1) return 0.0;
    best = std::min({best, box_distance(s.a.x_m, s.a.y_m, x0, x1, y0, y1),
                     box_distance(s.b.x_m, s.b.y_m, x0, x1, y0, y1)});
    for (const Point2& c : corners) {
      const Point2 q = closest_on_segment(s, c);
      best = std::min(best, std::hypot(q.x_m - c.x_m, q.y_m - c.y_m));
    }
  }
  for (const Circle& c : scenario_.world.circles) {
    best = std::min(best, std::max(footprint_distance(c.center) - c.radius_m, 0.0));
  }
  return best;
}

double SimWorld::footprint_clearance_people() const {
  double best = footprint_distance({person_.x_m, person_.y_m}) - scenario_.person_radius_m;
  for (const Pedestrian& p : crowd_.people())
    best = std::min(best, footprint_distance(p.position) - p.radius_m);
  for (const auto& w : replayed_) {
    if (w) best = std::min(best, footprint_distance(w->at) - kReplayedRadiusM);
  }
  return std::max(best, 0.0);
}

}  // namespace sim
