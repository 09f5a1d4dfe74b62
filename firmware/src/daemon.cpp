#include "firmware/daemon.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <limits>
#include <system_error>

#include "firmware/task_table.hpp"

namespace firmware {

using core::Nanos;

namespace {
// A safety snapshot older than this means the supervisor task is not running.
constexpr Nanos kSnapshotMaxAge = std::chrono::milliseconds(100);
constexpr int64_t kNotYet = std::numeric_limits<int64_t>::max();
// A companion point older than this (policy at 30 Hz: 6 missed runs) is not tracked.
constexpr Nanos kGoalMaxAge = std::chrono::milliseconds(200);
// Odometry is moved forward by its velocity for at most this long.
constexpr double kMaxOdomLagS = 0.1;
// A command reaches the wheels within this (CAN, the motor controllers' reaction; the Scout's
// feedback comes every 20 ms): feedback older than that after a change does not show it yet.
constexpr Nanos kBaseReaction = std::chrono::milliseconds(150);

// The base's measured velocity, which carries its odometry on to a later time.
core::BodyVelocity measured_velocity(const BaseHealth& b) {
  return core::BodyVelocity{b.vx_mps, b.vy_mps, b.wz_radps};
}
}  // namespace

core::SupervisorConfig supervisor_config(const DaemonConfig& cfg) {
  const auto& s = cfg.supervisor;
  core::SupervisorConfig c;
  c.arming_time = core::from_ms(s.arming_time_ms);
  c.resume_after = core::from_ms(s.resume_after_ms);
  c.tracker_timeout = core::from_ms(s.tracker_timeout_ms);
  c.tracker_confidence_recover = core::from_ms(s.tracker_confidence_recover_ms);
  c.person_max_distance_m = s.person_max_distance_m;
  c.lidar_timeout = core::from_ms(s.lidar_timeout_ms);
  c.costmap_max_age = core::from_ms(s.costmap_max_age_ms);
  c.base_feedback_timeout = core::from_ms(s.base_feedback_timeout_ms);
  c.control_stall_timeout = core::from_ms(s.control_stall_timeout_ms);
  c.control_overruns_to_hold = static_cast<uint32_t>(s.control_overruns_to_hold);
  c.control_overrun_window = core::from_ms(s.control_overrun_window_ms);
  return c;
}

core::StopLimits stop_limits(const DaemonConfig& cfg) {
  return core::StopLimits{cfg.supervisor.stop_linear_decel_mps2,
                          cfg.supervisor.stop_angular_decel_radps2,
                          core::from_ms(cfg.supervisor.stop_max_time_ms)};
}

amfitrack::AmfitrackConfig amfitrack_config(const DaemonConfig& cfg) {
  const auto& t = cfg.tracker;
  amfitrack::AmfitrackConfig c;
  c.sensor_tx_id = static_cast<uint8_t>(t.sensor_tx_id);
  c.keepalive_period = core::from_ms(t.keepalive_period_ms);
  c.gate.quality_high_is_good = t.quality_high_is_good;
  c.gate.quality_bad_below = static_cast<uint8_t>(t.quality_bad_below);
  c.gate.quality_good_min = static_cast<uint8_t>(t.quality_good_min);
  c.gate.quaternion_norm_tolerance = t.quaternion_norm_tolerance;
  c.gate.max_age = core::from_ms(t.max_age_ms);
  c.gate.recover_frames = static_cast<uint32_t>(t.recover_frames);
  return c;
}

amfitrack::TrackerExtrinsics tracker_extrinsics(const DaemonConfig& cfg) {
  const auto& t = cfg.tracker;
  return amfitrack::TrackerExtrinsics{
      {t.source_x_m, t.source_y_m, t.source_z_m},
      {t.source_roll_rad, t.source_pitch_rad, t.source_yaw_rad},
      {t.sensor_in_body_roll_rad, t.sensor_in_body_pitch_rad, t.sensor_in_body_yaw_rad}};
}

amfitrack::ReconnectConfig tracker_reconnect_config(const DaemonConfig& cfg) {
  return amfitrack::ReconnectConfig{core::from_ms(cfg.tracker.reconnect_first_ms),
                                    core::from_ms(cfg.tracker.reconnect_max_ms)};
}

core::HumanEkfConfig human_ekf_config(const DaemonConfig& cfg) {
  const auto& h = cfg.human;
  core::HumanEkfConfig c;
  c.position_noise_m = h.position_noise_m;
  c.heading_noise_rad = h.heading_noise_rad;
  c.yaw_rate_noise_radps = h.yaw_rate_noise_radps;
  c.accel_noise_mps2 = h.accel_noise_mps2;
  c.yaw_accel_noise_radps2 = h.yaw_accel_noise_radps2;
  c.prediction_time_constant_s = h.prediction_time_constant_s;
  c.prediction_turn_time_constant_s = h.prediction_turn_time_constant_s;
  c.prediction_heading_turn_time_constant_s = h.prediction_heading_turn_time_constant_s;
  c.gate_probability = h.gate_probability;
  c.reset_after_rejects = static_cast<uint32_t>(h.reset_after_rejects);
  c.reset_after_gap = core::from_ms(h.reset_after_gap_ms);
  return c;
}

core::TrackerConfidence to_tracker_confidence(amfitrack::Confidence c) {
  switch (c) {
    case amfitrack::Confidence::kGood:
      return core::TrackerConfidence::kGood;
    case amfitrack::Confidence::kDegraded:
      return core::TrackerConfidence::kDegraded;
    case amfitrack::Confidence::kBad:
      return core::TrackerConfidence::kBad;
  }
  return core::TrackerConfidence::kUnknown;
}

core::ClosingSpeedConfig closing_speed_config(const DaemonConfig& cfg) {
  core::ClosingSpeedConfig c;
  c.robot_decel_mps2 = cfg.closing_speed.robot_decel_mps2;
  c.person_accel_mps2 = cfg.closing_speed.person_accel_mps2;
  c.reaction_time_s = cfg.closing_speed.reaction_time_s;
  c.margin_m = cfg.closing_speed.margin_m;
  c.person_radius_m = cfg.closing_speed.person_radius_m;
  c.footprint = core::Footprint{cfg.costmap.footprint_x_min_m, cfg.costmap.footprint_x_max_m,
                                cfg.costmap.footprint_y_min_m, cfg.costmap.footprint_y_max_m};
  return c;
}

core::InteractiveSpaceConfig interactive_space_config(const DaemonConfig& cfg) {
  core::InteractiveSpaceConfig c;
  c.points = static_cast<int>(cfg.interactive_space.points);
  c.a_m = cfg.interactive_space.ellipse_a_m;
  c.b_m = cfg.interactive_space.ellipse_b_m;
  c.cost_threshold = cfg.interactive_space.cost_threshold;
  c.alpha = cfg.objective.alpha;
  c.beta = cfg.objective.beta;
  c.gamma = cfg.objective.gamma;
  c.delta = cfg.objective.delta;
  c.switch_cost = cfg.objective.switch_cost;
  c.turn_inside = cfg.objective.turn_inside;
  c.speed_standoff = cfg.interactive_space.speed_standoff;
  c.speed_standoff_max_m = cfg.interactive_space.speed_standoff_max_m;
  c.speed_standoff_filter_s = cfg.interactive_space.speed_standoff_filter_s;
  c.closing = closing_speed_config(cfg);
  return c;
}

core::PolicyLoadResult load_configured_policy(const DaemonConfig& cfg) {
  if (cfg.policy.file.empty()) return {};
  const auto n = static_cast<uint32_t>(cfg.interactive_space.points);
  return core::load_policy_file(cfg.policy.file, core::kObservationLayout, n,
                                static_cast<uint32_t>(core::observation_size(n)));
}

core::MppiConfig mppi_config(const DaemonConfig& cfg) {
  const auto& m = cfg.mppi;
  core::MppiConfig c;
  c.horizon_steps = static_cast<int>(m.horizon_steps);
  c.step_s = m.step_s;
  c.samples = static_cast<int>(m.samples);
  c.lambda = m.lambda;
  c.min_effective_samples = static_cast<int>(m.min_effective_samples);
  c.sigma = {m.noise_vx_mps, m.noise_vy_mps, m.noise_wz_radps};
  c.q = {m.q_x, m.q_y, m.q_theta};
  c.tracking_frame =
      m.tracking_frame == "robot" ? core::TrackingFrame::kRobot : core::TrackingFrame::kGoal;
  c.terminal_weight = m.terminal_weight;
  c.collision_cost = m.collision_cost;
  c.cost_threshold = cfg.interactive_space.cost_threshold;
  c.contact_cost = m.contact_cost;
  c.guide_samples = m.guide_samples;
  c.path_guide = m.path_guide;
  c.orbit_guide = m.orbit_guide;
  c.closing = closing_speed_config(cfg);
  // The footprint can touch an obstacle closer than its circumscribed radius.
  c.contact_threshold = core::cost_at_distance(
      core::CostmapConfig{cfg.costmap.inscribed_radius_m, cfg.costmap.inflation_radius_m,
                          cfg.costmap.cost_scaling_per_m},
      c.closing.footprint.circumscribed_radius_m());
  c.dcbf_delta = cfg.dcbf.delta;
  c.c_safe = cfg.dcbf.c_safe;
  c.ellipse = core::Ellipse{cfg.interactive_space.ellipse_a_m, cfg.interactive_space.ellipse_b_m};
  c.limits =
      core::TwistLimits{cfg.limits.vx_max_mps, cfg.limits.vy_max_mps, cfg.limits.wz_max_radps};
  c.reverse_speed_max_mps = m.reverse_speed_max_mps;
  c.guide_heading_gain_per_s = m.guide_heading_gain_per_s;
  c.obstacle_speed.robot_decel_mps2 = cfg.obstacle_speed.robot_decel_mps2;
  c.obstacle_speed.reaction_time_s = cfg.obstacle_speed.reaction_time_s;
  c.obstacle_speed.margin_m = cfg.obstacle_speed.margin_m;
  c.obstacle_speed.settled_s = cfg.obstacle_speed.settled_s;
  c.obstacle_speed.footprint = c.closing.footprint;
  c.linear_accel_mps2 = cfg.limits.linear_accel_max_mps2;
  c.angular_accel_radps2 = cfg.limits.angular_accel_max_radps2;
  c.threads = static_cast<int>(m.threads);
  c.seed = static_cast<uint64_t>(m.seed);
  return c;
}

core::PidFollowerConfig pid_follower_config(const DaemonConfig& cfg) {
  core::PidFollowerConfig c;
  c.limits =
      core::TwistLimits{cfg.limits.vx_max_mps, cfg.limits.vy_max_mps, cfg.limits.wz_max_radps};
  c.linear_accel_mps2 = cfg.limits.linear_accel_max_mps2;
  c.angular_accel_radps2 = cfg.limits.angular_accel_max_radps2;
  return c;
}

int side_sector(int index, int points) {
  if (index < 0 || points <= 0) return -1;
  // phi = 0 is ahead of the person, counter-clockwise: 90 deg is their left.
  return (8 * index + points / 2) / points % 8;  // nearest eighth of the circle
}

const char* side_name(int sector) {
  static constexpr std::array<const char*, 8> kSide = {"front",       "front-left", "left",
                                                       "behind-left", "behind",     "behind-right",
                                                       "right",       "front-right"};
  return sector >= 0 && sector < 8 ? kSide[static_cast<size_t>(sector)] : "-";
}

const char* side_of_person(int index, int points) {
  return side_name(side_sector(index, points));
}

namespace {
// Odometry kept for placing tracker frames: 64 poses at 50 Hz = 1.3 s; a frame newer than the
// newest pose uses it for up to 40 ms (two base periods).
constexpr size_t kOdomHistory = 64;
constexpr Nanos kOdomHold = std::chrono::milliseconds(40);
}  // namespace

Daemon::Daemon(const DaemonConfig& cfg, hal::SystemdNotifier& notifier)
    : cfg_(cfg),
      notifier_(notifier),
      supervisor_(supervisor_config(cfg)),
      watchdog_interval_(hal::SystemdNotifier::watchdog_interval()),
      person_frame_(tracker_extrinsics(cfg)),
      human_config_(human_ekf_config(cfg)),
      human_ekf_(human_config_),
      odom_history_(kOdomHistory, kOdomHold),
      tracker_warning_(core::from_ms(cfg.logging.warning_interval_ms)),
      lidar_odom_(kOdomHistory, kOdomHold),
      lidar_warning_(core::from_ms(cfg.logging.warning_interval_ms)),
      space_(interactive_space_config(cfg)),
      selector_(cfg.policy.selector == "objective"      ? Selector::kObjective
                : cfg.policy.selector == "fixed_behind" ? Selector::kFixedBehind
                : cfg.policy.selector == "fixed_side"   ? Selector::kFixedSide
                                                        : Selector::kAuto),
      standoff_velocity_(space_.config()),
      goal_slew_(cfg.objective.slew_points_per_s),
      goal_hold_(core::from_ms(std::llround(cfg.policy.hold_last_point_ms))),
      mppi_(mppi_config(cfg)),
      pid_(pid_follower_config(cfg)),
      use_pid_(cfg.control.controller == "pid_follower"),
      person_path_(static_cast<size_t>(cfg.mppi.horizon_steps) + 1),
      goal_path_(person_path_.size()),
      goal_heading_path_(person_path_.size()),
      gate_(stop_limits(cfg)),
      base_send_warning_(core::from_ms(cfg.logging.warning_interval_ms)) {}

void Daemon::attach(const Executor& executor) {
  executor_ = &executor;
  const size_t control = executor.find("control");
  control_stats_ = control < executor.task_count() ? &executor.stats(control) : nullptr;
}

std::vector<TaskBinding> Daemon::bindings() {
  std::vector<TaskBinding> out;
  for (const TaskRow& row : task_table()) {
    const DaemonTaskFn fn = row.fn;
    out.push_back(TaskBinding{row.spec, [this, fn](const core::Tick& t) { (this->*fn)(t); }});
  }
  return out;
}

bool Daemon::shutdown_complete() const {
  if (!shutdown_.load(std::memory_order_acquire)) return false;
  const auto s = safety_.read();
  const auto c = command_.read();
  const bool commanded_zero = s && s->value.reason == core::Reason::kShutdown && c &&
                              c->value.is_zero() && c->stamp >= s->stamp;
  if (!commanded_zero || !base_) return commanded_zero;
  // With a base: its own feedback must confirm standstill, measured long enough after the zero
  // command took over that a command still in the base's pipeline would show (a base that has
  // not started moving yet also reports zero).
  const auto b = base_health_.read();
  const int64_t zero_since = zero_commanded_since_ns_.load(std::memory_order_acquire);
  if (zero_since == kNotYet) return false;
  return b && b->value.feedback_stamp != core::kNever &&
         b->value.feedback_stamp > Nanos(zero_since) + kBaseReaction && b->value.vx_mps == 0.0 &&
         b->value.vy_mps == 0.0 && b->value.wz_radps == 0.0;
}

// ---- tracker: Amfitrack frames -> gate -> person in base_link -> human filter in odom ---------

void Daemon::attach_tracker(std::unique_ptr<amfitrack::PacketLink> link) {
  tracker_link_ = std::move(link);
  tracker_ = std::make_unique<amfitrack::Amfitrack>(*tracker_link_, amfitrack_config(cfg_));
  // Resolved once here, not per run: a reconnecting link also reports why it is down.
  const amfitrack::PacketLink* inner = tracker_link_.get();
  if (const auto* tap = dynamic_cast<const amfitrack::TapLink*>(inner)) inner = &tap->inner();
  tracker_reconnecting_ = dynamic_cast<const amfitrack::ReconnectingLink*>(inner);
}

void Daemon::tracker_link_events(Nanos now) {
  const amfitrack::ReconnectingLink* rl = tracker_reconnecting_;
  const bool up = !tracker_link_->failed();
  if (up != tracker_link_was_up_) {
    if (up) {
      // A link that is not reopened by us (the simulator's, a test's) has no description.
      spdlog::info("tracker: link up{}", rl != nullptr ? ": " + rl->events().description : "");
    } else {
      spdlog::warn("tracker: link lost ({}); reopening with back-off",
                   rl != nullptr ? rl->events().last_error : std::string("read/write error"));
    }
    tracker_link_was_up_ = up;
  }
  if (rl != nullptr && rl->events().open_failures != tracker_open_failures_seen_) {
    tracker_open_failures_seen_ = rl->events().open_failures;
    tracker_warning_.warn(now, "tracker: cannot open: {} (attempt {}, next in back-off)",
                          rl->events().last_error, tracker_open_failures_seen_);
  }
}

void Daemon::tracker_task(const core::Tick& tick) {
  if (!tracker_) return;
  tracker_->poll(tick.now);
  tracker_link_events(tick.now);

  // Where the robot was when each frame arrived (wheel odometry; identity without a base).
  if (const auto b = base_health_.read(); b && b->value.odom_stamp != core::kNever) {
    odom_history_.add(b->value.odom, b->value.odom_stamp, measured_velocity(b->value));
  }
  for (const amfitrack::StampedMeasurement& sm : tracker_->new_measurements()) {
    const auto person = person_frame_.to_base(sm.m);
    if (!person) continue;
    person_distance_m_ = person->distance_m;
    // A frame the gate calls BAD (no tracking, distorted field) is not a measurement.
    if (sm.confidence == amfitrack::Confidence::kBad) continue;
    core::Pose2 base_in_odom;
    if (base_) {
      const auto at = odom_history_.at(sm.stamp);
      if (!at) continue;  // no odometry near this frame: cannot place it in odom
      base_in_odom = *at;
    }
    const core::Pose2 person_in_odom =
        base_in_odom * core::Pose2{person->x_m, person->y_m, person->heading_rad};
    human_ekf_.update_pose(person_in_odom, person->heading_valid, sm.stamp);
    if (cfg_.human.use_gyro) human_ekf_.update_yaw_rate(person->yaw_rate_radps, sm.stamp);
  }
  if (!tracker_->new_measurements().empty()) {
    human_track_.publish(human_ekf_.track(), tick.now);
  }

  const amfitrack::GateOutput gate = tracker_->confidence(tick.now);
  TrackerHealth h;
  if (const auto& latest = tracker_->latest()) h.frame_stamp = latest->stamp;
  h.person_distance_m = person_distance_m_;  // of the newest frame with a valid pose
  h.confidence = to_tracker_confidence(gate.confidence);
  h.gate_reason = gate.reason;
  h.quality = gate.quality;
  h.rate_hz = tracker_->rate_hz();
  h.link_up = !tracker_->link_failed();
  const auto& c = tracker_->counters();
  h.frames = c.poses;
  h.dropped_frames = c.dropped_frames;
  const amfitrack::FramingStats fs = tracker_link_->framing_stats();
  h.decode_errors = fs.bad_cobs + fs.overlong + fs.bad_packet;
  for (uint64_t e : c.payload_errors)
    h.decode_errors += e;
  h.filter_rejected = human_ekf_.counters().rejected;
  h.filter_resets = human_ekf_.counters().resets;
  tracker_health_.publish(h, tick.now);
}

bool Daemon::attach_base(std::unique_ptr<hal::CanBus> bus) {
  uint8_t base_group = 0;
  uint8_t control_group = 1;
  for (const TaskRow& row : task_table()) {
    if (row.spec.name == "base") base_group = row.spec.group;
    if (row.spec.name == "control") control_group = row.spec.group;
  }
  if (base_group != control_group) return false;
  scout_mini::ScoutConfig sc;
  sc.limits = {cfg_.limits.vx_max_mps, cfg_.limits.vy_max_mps, cfg_.limits.wz_max_radps};
  sc.feedback_timeout = core::from_ms(cfg_.supervisor.base_feedback_timeout_ms);
  base_bus_ = std::move(bus);
  base_ = std::make_unique<scout_mini::ScoutMini>(*base_bus_, sc);
  return true;
}

// ---- base: Scout Mini feedback, CAN mode, health for the supervisor ---------------------------

void Daemon::base_task(const core::Tick& tick) {
  if (!base_) return;
  base_->poll(tick.now);
  const auto& st = base_->state();
  BaseHealth h;
  h.feedback_stamp = base_->last_feedback() == Nanos(0) ? core::kNever : base_->last_feedback();
  h.stopping_faults = st.stopping_faults();
  h.fault_word = st.fault_word;
  h.estop = st.estop();
  h.rc_override = st.rc_has_control();
  h.bus_off = base_->bus_off();
  h.can_mode = st.in_can_mode();
  h.write_errors = base_->counters().write_errors;
  h.vx_mps = st.velocity.vx_mps;
  h.vy_mps = st.velocity.vy_mps;
  h.wz_radps = st.velocity.wz_radps;
  h.odom = core::Pose2{st.odom.x_m, st.odom.y_m, st.odom.theta_rad};
  h.odom_stamp = base_->odom_stamp() == Nanos(0) ? core::kNever : base_->odom_stamp();
  base_health_.publish(h, tick.now);
}
// ---- lidar: VLP-16 packets -> scans -> voxel grid -> costmap snapshot --------------------------

void Daemon::attach_lidar(std::unique_ptr<hal::DatagramSource> data) {
  lidar_rx_ = std::move(data);
  lidar_ = std::make_unique<LidarPipeline>(cfg_);
}

void Daemon::lidar_task(const core::Tick& tick) {
  if (!lidar_) return;
  if (const auto b = base_health_.read(); b && b->value.odom_stamp != core::kNever) {
    lidar_odom_.add(b->value.odom, b->value.odom_stamp, measured_velocity(b->value));
  }
  std::optional<core::HumanTrack> person;
  if (const auto h = human_track_.read(); h && h->value.valid) person = h->value;
  // A 10 Hz run drains ~75 packets (150 in dual-return mode); the bound keeps a flood from
  // stalling the task (the kernel counts what overflows).
  constexpr size_t kMaxPacketsPerRun = 1000;
  lidar_rx_->drain(kMaxPacketsPerRun, tick.now, [&](const hal::UdpDatagram& d) {
    vlp16::RawDataPacket raw;
    const vlp16::DecodeError e = vlp16::parse_data_packet(d.bytes, raw);
    if (e != vlp16::DecodeError::kNone) {
      ++lidar_state_.decode_errors;
      lidar_warning_.warn(tick.now, "lidar: dropped a {}-byte datagram: {} ({} so far)",
                          d.bytes.size(), vlp16::to_string(e), lidar_state_.decode_errors);
      return;
    }
    ++lidar_state_.packets;
    lidar_state_.packet_stamp = d.stamp;
    const uint64_t unplaced = lidar_->scans_without_pose();
    const core::Costmap* m = lidar_->add_packet(raw, d.stamp, lidar_odom_, person);
    if (lidar_->scans_without_pose() != unplaced) {
      lidar_warning_.warn(tick.now, "lidar: scan not used: no odometry at its time ({} so far)",
                          lidar_->scans_without_pose());
    }
    if (m == nullptr) return;
    ++lidar_state_.scans;
    lidar_state_.costmap_stamp = m->stamp();
    lidar_state_.obstacle_cells = m->obstacle_cells();
    if (core::Costmap* out = costmap_.begin_write()) {
      out->copy_cells_from(*m);  // into a spare buffer (allocates only the first time)
      costmap_.publish();
    }
  });
  lidar_state_.lost_packets = lidar_->assembler().stats().lost_packets;
  lidar_state_.kernel_drops = lidar_rx_->stats().kernel_drops;
  lidar_health_.publish(lidar_state_, tick.now);
}
// ---- policy: the companion point q^d (objective argmin; the learned policy: issue 6) -----------

void Daemon::attach_policy(core::PolicyFile policy) {
  policy_ = std::make_unique<core::MlpPolicy>(std::move(policy));
  observation_.assign(core::observation_size(static_cast<size_t>(space_.config().points)), 0.0f);
}

void Daemon::policy_task(const core::Tick& tick) {
  CompanionGoal g;
  g.points = space_.config().points;
  const auto track = human_track_.read();
  const auto map = costmap_.latest();
  core::Pose2 robot_odom;
  if (const auto b = base_health_.read(); b && b->value.odom_stamp != core::kNever) {
    robot_odom = b->value.odom;
  }
  if (!track || !track->value.valid) {
    g.status = core::GoalStatus::kNoPerson;
    standoff_velocity_.reset();
  } else if (!map) {
    g.status = core::GoalStatus::kNoCostmap;
  } else {
    const auto th = tracker_health_.read();
    const core::HumanState h =
        core::human_state(track->value, tick.now, robot_odom, human_config_,
                          th ? th->value.confidence : core::TrackerConfidence::kUnknown);
    const core::Point2 velocity_base =
        standoff_velocity_.base(h.velocity_odom, h.velocity_base, robot_odom, tick.now);
    space_.update(h.pose_base, robot_odom, *map, velocity_base, h.yaw_rate_radps);
    core::Selection s = core::select_by_objective(space_, goal_hold_.index());
    bool objective_chose = true;  // false below when a baseline or the policy chooses instead
    if (selector_ == Selector::kFixedBehind || selector_ == Selector::kFixedSide) {
      // Evaluation baselines: one point of W, free or not (phi = pi behind, pi/2 the left side).
      const bool behind = selector_ == Selector::kFixedBehind;
      const int n = space_.config().points;
      const int index = behind ? n / 2 : n / 4;
      s.status = core::GoalStatus::kOk;
      s.index = index;
      s.goal_base = space_.candidates()[static_cast<size_t>(index)].base;
      g.selector = behind ? "fixed_behind" : "fixed_side";
      objective_chose = false;
    } else if (policy_ && selector_ == Selector::kAuto && s.status == core::GoalStatus::kOk) {
      // The learned selector: the paper's observation, masked argmax over P.
      core::ObservationInputs oi;
      oi.space = &space_;
      oi.costmap = map.get();
      oi.robot_odom = robot_odom;
      if (const auto b = base_health_.read()) {
        oi.robot_vx_mps = b->value.vx_mps;
        oi.robot_vy_mps = b->value.vy_mps;
        oi.robot_wz_radps = b->value.wz_radps;
      }
      oi.human = h;
      oi.previous_action = goal_hold_.index();
      const auto cs = space_.candidates();
      std::array<bool, 1024> mask{};
      for (size_t i = 0; i < cs.size() && i < mask.size(); ++i)
        mask[i] = cs[i].free;
      if (core::build_observation(oi, observation_)) {
        const int a = policy_->select(observation_, std::span<const bool>(mask.data(), cs.size()));
        if (a >= 0) {
          s.index = a;
          s.goal_base = cs[static_cast<size_t>(a)].base;
          g.selector = "policy";
          objective_chose = false;
        }
      }
    }
    if (objective_chose) {  // neither a baseline's fixed point nor the policy's
      s = goal_slew_.update(s, goal_hold_.index(), space_, tick.period);
    }
    s = goal_hold_.update(s, space_, tick.now);
    g.held = goal_hold_.held();
    g.status = s.status;
    g.index = s.index;
    g.free_points = space_.free_count();
    g.goal_base = s.goal_base;
    g.goal_odom = robot_odom * s.goal_base;
    g.person_odom = h.pose_odom;
  }
  goal_.publish(g, tick.now);
}

// ---- control: everything that can move the robot passes the supervisor's gate ---------------

void Daemon::control_task(const core::Tick& tick) {
  const auto safety = safety_.read();
  const bool allowed = safety && safety->value.motion_allowed;
  // Track q^d only with everything the controller needs, fresh; otherwise the gate stops the
  // robot the controlled way (the supervisor says why when an input is missing).
  core::BodyVelocity requested{};
  bool tracking = false;
  if (allowed) {
    tracking =
        use_pid_ ? run_pid_follower(tick.now, requested) : run_controller(tick.now, requested);
  }
  if (!tracking) {  // a later start must not follow a stale plan
    mppi_.reset();
    pid_.reset();
  }
  control_state_.tracking = tracking;
  const core::BodyVelocity cmd = gate_.update(allowed && tracking, requested, tick.now);
  last_command_ = core::Twist{cmd.vx_mps, cmd.vy_mps, cmd.wz_radps};
  if (shutdown_.load(std::memory_order_acquire) && cmd.is_zero()) {
    if (zero_commanded_since_ns_.load(std::memory_order_relaxed) == kNotYet) {
      zero_commanded_since_ns_.store(tick.now.count(), std::memory_order_release);
    }
  } else {
    zero_commanded_since_ns_.store(kNotYet, std::memory_order_release);
  }
  control_state_.command = cmd;
  command_.publish(cmd, tick.now);
  control_status_.publish(control_state_, tick.now);
  // Every path to the wheels passes the gate above; a zero command is still streamed (the base
  // stops by itself 500 ms after the last one).
  if (base_) {
    const hal::CanSendResult r = base_->command(cmd.vx_mps, cmd.vy_mps, cmd.wz_radps, tick.now);
    if (r != hal::CanSendResult::kOk) {
      // Repeats at 100 Hz while the bus is down: one line per interval, with the count.
      base_send_warning_.warn(tick.now, "base: motion command not sent: {} (write errors {})",
                              hal::to_string(r), base_->counters().write_errors);
    }
  }
}

bool Daemon::run_pid_follower(Nanos now, core::BodyVelocity& requested) {
  const auto track = human_track_.read();
  const auto base = base_health_.read();
  if (!track || !track->value.valid || !base || base->value.odom_stamp == core::kNever) {
    return false;
  }
  const core::HumanState h = core::human_state(track->value, now, base->value.odom, human_config_);
  const core::Twist u = pid_.step({h.pose_base.x_m, h.pose_base.y_m}, now);
  ++control_state_.runs;
  requested = core::BodyVelocity{u.vx, u.vy, u.wz};
  return true;
}

bool Daemon::run_controller(Nanos now, core::BodyVelocity& requested) {
  const auto goal = goal_.read();
  const auto track = human_track_.read();
  const auto base = base_health_.read();
  if (!goal || goal->value.status != core::GoalStatus::kOk || now - goal->stamp > kGoalMaxAge) {
    return false;
  }
  if (!track || !track->value.valid || !base || base->value.odom_stamp == core::kNever) {
    return false;
  }
  // The robot now: the newest wheel odometry moved on by its measured velocity (feedback comes
  // every 20 ms; at 1 m/s that is 2 cm of lag otherwise).
  const BaseHealth& b = base->value;
  const double lag_s = std::clamp(core::to_seconds(now - b.odom_stamp), 0.0, kMaxOdomLagS);
  const core::Pose2 robot = core::carried(b.odom, measured_velocity(b), lag_s);
  // The person for the barrier: constant velocity, the conservative prediction of where they
  // may be. q^d, the point to be at, walks with them on a velocity that fades with
  // human.prediction_time_constant_s (2 s by default), so it stays on the costmap; at constant
  // velocity (0) it runs ~15 m ahead over the 10 s horizon, off the map (docs/EVALUATION.md).
  // q^d's turn rate fades with human.prediction_turn_time_constant_s when set (0: as the
  // velocity); the barrier's person keeps a constant turn rate.
  // q^d is a point of the person's interactive space: it walks with them over the horizon.
  const core::Pose2 goal_in_person = goal->value.goal_in_person();
  core::predict_person_and_goal_paths(track->value, now, mppi_.config().step_s, human_config_,
                                      goal_in_person, person_path_, goal_path_);
  // q^d's heading may stop turning sooner than its place (human.
  // prediction_heading_turn_time_constant_s): the base turns on the spot.
  const double heading_turn_s = human_config_.prediction_heading_turn_time_constant_s;
  if (heading_turn_s > 0.0) {
    core::predict_goal_headings(track->value, now, mppi_.config().step_s, heading_turn_s,
                                goal_in_person.theta_rad, goal_heading_path_);
  }
  const auto map = costmap_.latest();

  core::MppiInputs in;
  in.robot = robot;
  in.current = last_command_;
  in.goal = goal->value.goal_odom;
  in.goal_path = goal_path_;
  if (heading_turn_s > 0.0) in.goal_heading_path = goal_heading_path_;
  in.person = person_path_;
  in.costmap = map.get();
  in.now = now;
  const core::MppiOutput out = mppi_.step(in);
  ++control_state_.runs;
  if (!out.ok) {
    ++control_state_.failures;
    if (!control_state_.numerical_failure) {
      spdlog::error(
          "control: MPPI numerical failure at run {} (robot {:.3f} {:.3f} {:.3f}, goal "
          "{:.3f} {:.3f} {:.3f}): stopping",
          control_state_.runs, robot.x_m, robot.y_m, robot.theta_rad, in.goal.x_m, in.goal.y_m,
          in.goal.theta_rad);
    }
    control_state_.numerical_failure = true;  // the supervisor latches FAULT
    return false;
  }
  control_state_.repaired = out.repaired;
  if (out.repaired) ++control_state_.repairs;
  if (out.closing_limited) ++control_state_.closing_limits;
  if (out.obstacle_limited) ++control_state_.obstacle_limits;
  if (out.guided) ++control_state_.guided_plans;
  if (out.path_planned) ++control_state_.paths_planned;
  if (out.path_guided) ++control_state_.path_guided_plans;
  if (out.orbit_planned) ++control_state_.orbits_planned;
  if (out.orbit_guided) ++control_state_.orbit_guided_plans;
  control_state_.min_cost = out.min_cost;
  control_state_.best_cost = out.best;
  control_state_.effective_samples = out.effective_samples;
  requested = core::BodyVelocity{out.command.vx, out.command.vy, out.command.wz};
  return true;
}

// ---- supervisor ------------------------------------------------------------------------------

void Daemon::supervisor_task(const core::Tick& tick) {
  core::SafetyInputs in;
  in.initialized = initialized_.load(std::memory_order_acquire);
  in.shutdown = shutdown_.load(std::memory_order_acquire);
  if (in.initialized && initialized_at_ == core::kNever) initialized_at_ = tick.now;

  if (control_stats_ != nullptr) {
    // Before the control task's first run, its heartbeat counts from start-up.
    in.control_heartbeat =
        control_stats_->runs() > 0 ? control_stats_->last_end() : initialized_at_;
    in.control_overruns = control_stats_->overruns();
  }

  if (const auto t = tracker_health_.read()) {
    const TrackerHealth& h = t->value;
    in.tracker_stamp = h.frame_stamp;
    in.tracker_confidence = h.confidence;
    in.tracker_detail = amfitrack::to_string(h.gate_reason).data();  // static text
    in.tracker_quality = h.quality;
    in.person_distance_m = h.person_distance_m;
  }

  if (const auto c = control_status_.read()) in.numerical_failure = c->value.numerical_failure;

  if (const auto l = lidar_health_.read()) {
    in.lidar_stamp = l->value.packet_stamp;
    in.costmap_stamp = l->value.costmap_stamp;
  }

  if (const auto base = base_health_.read()) {
    const BaseHealth& h = base->value;
    in.base_feedback_stamp = h.feedback_stamp;
    in.base_fault_word = h.stopping_faults;
    in.base_estop = h.estop;
    in.rc_override = h.rc_override;
    in.can_bus_off = h.bus_off;
    in.can_write_errors = h.write_errors;
  }

  const core::SupervisorOutput out = supervisor_.update(in, tick.now);
  if (out.transitioned) {
    const auto& tr = out.transition;
    const bool bad = tr.to == core::SafetyState::kHold || tr.to == core::SafetyState::kFault;
    const std::string line =
        tr.reason == core::Reason::kNone
            ? fmt::format("{} -> {} ({})", core::state_name(tr.from), core::state_name(tr.to),
                          tr.values.data())
            : fmt::format("{} -> {}: {} [reason {} {}] ({})", core::state_name(tr.from),
                          core::state_name(tr.to), core::reason_text(tr.reason),
                          static_cast<int>(tr.reason), core::reason_name(tr.reason),
                          tr.values.data());
    if (bad) {
      spdlog::warn("safety: {}", line);
    } else {
      spdlog::info("safety: {}", line);
    }
  }

  SafetySnapshot snap;
  snap.state = out.state;
  snap.reason = out.reason;
  snap.motion_allowed = out.motion_allowed;
  snap.watchdog_ok = out.watchdog_ok;
  snap.active_mask = static_cast<uint32_t>(out.active.to_ulong());
  safety_.publish(snap, tick.now);
}

// ---- notify: systemd watchdog, off the real-time threads ----------------------------------------

void Daemon::notify_task(const core::Tick& tick) {
  // The supervisor decides (control task progressing); this task only sends, on a non-real-time
  // thread, because a notification socket that is not read blocks the sender. A supervisor that
  // stopped publishing (stale snapshot) stops the pings too.
  if (!watchdog_interval_) return;
  const auto s = safety_.read();
  if (!s || !s->value.watchdog_ok || tick.now - s->stamp > kSnapshotMaxAge) return;
  const Nanos every = std::chrono::duration_cast<Nanos>(*watchdog_interval_) / 4;
  if (last_watchdog_ping_ == core::kNever || tick.now - last_watchdog_ping_ >= every) {
    notifier_.watchdog();
    last_watchdog_ping_ = tick.now;
  }
}

// ---- report: status line, summaries (not real-time) ------------------------------------------

std::string Daemon::safety_text(const SafetySnapshot& s) const {
  std::string text(core::state_name(s.state));
  if (s.reason != core::Reason::kNone) text += fmt::format(": {}", core::reason_text(s.reason));
  std::string others;
  int n_others = 0;
  for (size_t i = 0; i < core::kReasonCount; ++i) {
    if ((s.active_mask >> i & 1U) != 0 && core::kReasonTable[i].reason != s.reason) {
      others += fmt::format("{}{}", others.empty() ? "" : ", ", core::kReasonTable[i].text);
      ++n_others;
    }
  }
  if (n_others > 0) text += fmt::format(" (also: {})", others);
  return text;
}

void Daemon::report_task(const core::Tick& tick) {
  if (executor_ == nullptr) return;
  const size_t n = executor_->task_count();
  if (last_runs_.size() != n) {
    last_runs_.assign(n, 0);
    measured_rate_hz_.assign(n, std::numeric_limits<double>::quiet_NaN());
  }
  // Rate = runs between two reports over the time between their last starts: exact for a task
  // on time (no +-1 run quantisation of a fixed window), lower when it skips releases.
  if (last_starts_.size() != n) last_starts_.assign(n, core::kNever);
  for (size_t i = 0; i < n; ++i) {
    const core::TaskStats& st = executor_->stats(i);
    const uint64_t runs = st.runs();
    const Nanos start = runs > 0 ? st.last_start() : core::kNever;
    if (last_starts_[i] != core::kNever && start != core::kNever && start > last_starts_[i]) {
      measured_rate_hz_[i] =
          static_cast<double>(runs - last_runs_[i]) / core::to_seconds(start - last_starts_[i]);
    } else if (last_starts_[i] != core::kNever) {
      measured_rate_hz_[i] = 0.0;  // no run since the previous report
    } else {
      measured_rate_hz_[i] = std::numeric_limits<double>::quiet_NaN();  // not measured yet
    }
    last_runs_[i] = runs;
    last_starts_[i] = start;
  }

  const auto safety = safety_.read();
  std::string line = safety ? safety_text(safety->value) : std::string("INIT: starting up");
  std::string rates;
  std::string shells;
  for (size_t i = 0; i < n; ++i) {
    const auto& spec = executor_->spec(i);
    const double hz = measured_rate_hz_[i];
    rates += std::isnan(hz) ? fmt::format("{}{} -Hz", rates.empty() ? "" : " ", spec.name)
                            : fmt::format("{}{} {:.0f}Hz", rates.empty() ? "" : " ", spec.name, hz);
    for (const TaskRow& row : task_table()) {
      if (row.spec.name == spec.name && !row.pending.empty()) {
        shells += fmt::format("{}{}", shells.empty() ? "" : ", ", spec.name);
      }
    }
  }
  if (tracker_) line += " | " + tracker_text(tick.now);
  if (lidar_) line += " | " + lidar_text(tick.now);
  if (const auto g = goal_.read(); g && (tracker_ || lidar_)) {
    const CompanionGoal& v = g->value;
    line += v.status == core::GoalStatus::kOk
                ? fmt::format(" | goal {} {} of the person ({:+.2f}, {:+.2f}) m, {}/{} free{}",
                              v.selector, side_of_person(v.index, v.points), v.goal_base.x_m,
                              v.goal_base.y_m, v.free_points, v.points,
                              v.held ? " (held: no free point)" : "")
                : fmt::format(" | goal none: {}", core::to_string(v.status));
  }
  line += " | " + rates;
  if (!shells.empty()) line += " | not yet implemented: " + shells;
  std::string compact;
  for (size_t i = 0; i < n; ++i) {
    const double hz = measured_rate_hz_[i];
    compact += fmt::format("{}{} {}", compact.empty() ? "" : " ", executor_->spec(i).name,
                           std::isnan(hz) ? std::string("-") : fmt::format("{:.0f}", hz));
  }
  std::string json = build_status_json(tick.now);
  {
    const std::scoped_lock lock(report_mutex_);
    status_ = line;
    rates_ = std::move(compact);
    json_ = std::move(json);
  }
  if (line != last_status_sent_) {
    notifier_.status(line);
    last_status_sent_ = line;
  }
  write_status_file();

  const Nanos summary_every = std::chrono::duration_cast<Nanos>(
      std::chrono::duration<double>(cfg_.logging.summary_period_s));
  if (last_summary_ == core::kNever || tick.now - last_summary_ >= summary_every) {
    spdlog::info("status: {}", status_);
    spdlog::info("timing: {}", timing_summary());
    last_summary_ = tick.now;
  }
}

std::string Daemon::tracker_text(Nanos now) const {
  const auto t = tracker_health_.read();
  if (!t) return "tracker -";
  const TrackerHealth& h = t->value;
  if (!h.link_up) return "tracker link down";
  if (h.frame_stamp == core::kNever) return "tracker no frames";
  std::string s = fmt::format("tracker {}", core::confidence_name(h.confidence));
  if (h.gate_reason != amfitrack::GateReason::kNone) {
    s += fmt::format(" ({})", amfitrack::to_string(h.gate_reason));
  }
  s += fmt::format(" q{} {:.0f}Hz age {:.0f}ms", h.quality, h.rate_hz,
                   core::to_ms(now - h.frame_stamp));
  if (!std::isnan(h.person_distance_m)) s += fmt::format(" person {:.2f}m", h.person_distance_m);
  if (h.dropped_frames > 0) s += fmt::format(" drops {}", h.dropped_frames);
  if (h.decode_errors > 0) s += fmt::format(" errors {}", h.decode_errors);
  return s;
}

std::string Daemon::lidar_text(Nanos now) const {
  const auto l = lidar_health_.read();
  if (!l || l->value.packet_stamp == core::kNever) return "lidar no packets";
  const LidarHealth& h = l->value;
  std::string s =
      fmt::format("lidar {} pkts age {:.0f}ms", h.packets, core::to_ms(now - h.packet_stamp));
  if (h.costmap_stamp != core::kNever) {
    s += fmt::format(" costmap age {:.0f}ms obstacles {}", core::to_ms(now - h.costmap_stamp),
                     h.obstacle_cells);
  }
  if (h.lost_packets > 0) s += fmt::format(" lost {}", h.lost_packets);
  if (h.kernel_drops > 0) s += fmt::format(" drops {}", h.kernel_drops);
  if (h.decode_errors > 0) s += fmt::format(" errors {}", h.decode_errors);
  return s;
}

std::string Daemon::status_line() const {
  const std::scoped_lock lock(report_mutex_);
  return status_;
}

std::string Daemon::rates_text() const {
  const std::scoped_lock lock(report_mutex_);
  return rates_;
}

std::string Daemon::status_json() const {
  const std::scoped_lock lock(report_mutex_);
  return json_;
}

void Daemon::write_status_file() {
  if (status_file_.empty()) return;
  // Atomic replace: a reader never sees half a file.
  const std::string tmp = status_file_ + ".tmp";
  std::string json = status_json();
  std::FILE* f = std::fopen(tmp.c_str(), "w");
  bool ok = f != nullptr && std::fwrite(json.data(), 1, json.size(), f) == json.size();
  if (f != nullptr) ok = std::fclose(f) == 0 && ok;
  if (ok) ok = std::rename(tmp.c_str(), status_file_.c_str()) == 0;
  if (!ok && !status_file_warned_) {
    // std::error_code's message is thread-safe (strerror is not).
    spdlog::warn("status: cannot write {}: {} (not repeated in the log)", status_file_,
                 std::error_code(errno, std::generic_category()).message());
    status_file_warned_ = true;
  }
}

std::string Daemon::timing_summary() const {
  if (executor_ == nullptr) return {};
  std::string out;
  for (size_t i = 0; i < executor_->task_count(); ++i) {
    const auto& st = executor_->stats(i);
    const double rate = i < measured_rate_hz_.size() ? measured_rate_hz_[i]
                                                     : std::numeric_limits<double>::quiet_NaN();
    out += fmt::format(
        "{}{} {}Hz jitter p50/p99/max {:.0f}/{:.0f}/{:.0f}us run p99/max {:.0f}/{:.0f}us "
        "over {} skip {} budget {}",
        out.empty() ? "" : "; ", executor_->spec(i).name,
        std::isnan(rate) ? std::string("-") : fmt::format("{:.1f}", rate),
        core::to_us(st.period_jitter().quantile(0.5)),
        core::to_us(st.period_jitter().quantile(0.99)), core::to_us(st.period_jitter().max()),
        core::to_us(st.run_time().quantile(0.99)), core::to_us(st.run_time().max()), st.overruns(),
        st.skipped(), st.budget_exceeded());
  }
  return out;
}

}  // namespace firmware
