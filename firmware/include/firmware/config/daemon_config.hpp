#pragma once
// Typed configuration of companiond. Every field is listed, with its key, unit, range and
// meaning, in the schema (src/config/schema.cpp); defaults live in config/companiond.yaml.
#include <cstdint>
#include <string>

namespace firmware {

struct DaemonConfig {
  struct Devices {
    std::string
        tracker;  // hid:auto | hid:<hidraw path or serial> | serial:<port>[@baud] | sim | none
    std::string lidar;  // udp:<bind addr>:<port> | sim | none
    std::string base;   // socketcan:<ifname> | slcan:<tty> | virtual:<bus> | sim | none
  } devices;

  struct Tracker {
    int64_t sensor_tx_id = 0;
    int64_t keepalive_period_ms = 0;
    int64_t reconnect_first_ms = 0;
    int64_t reconnect_max_ms = 0;
    bool quality_high_is_good = true;
    int64_t quality_bad_below = 0;
    int64_t quality_good_min = 0;
    double quaternion_norm_tolerance = 0;
    int64_t max_age_ms = 0;
    int64_t recover_frames = 0;
    double source_x_m = 0, source_y_m = 0, source_z_m = 0;
    double source_roll_rad = 0, source_pitch_rad = 0, source_yaw_rad = 0;
    double sensor_in_body_roll_rad = 0, sensor_in_body_pitch_rad = 0, sensor_in_body_yaw_rad = 0;
  } tracker;

  struct Lidar {
    double x_m = 0, y_m = 0, z_m = 0;
    double roll_rad = 0, pitch_rad = 0, yaw_rad = 0;
    double cut_azimuth_deg = 0;
    double min_range_m = 0;
    double max_range_m = 0;
    int64_t receive_buffer_bytes = 0;
  } lidar;

  struct Costmap {
    double size_m = 0;
    double resolution_m = 0;
    double z_min_m = 0;
    double z_max_m = 0;
    double decay_s = 0;
    double clear_max_range_m = 0;
    bool clear_on_no_return = false;
    bool clear_seen_through = false;
    double hidden_decay_s = 0;
    double inscribed_radius_m = 0;
    double inflation_radius_m = 0;
    double cost_scaling_per_m = 0;
    double footprint_x_min_m = 0, footprint_x_max_m = 0;
    double footprint_y_min_m = 0, footprint_y_max_m = 0;
    double person_mask_radius_m = 0;
  } costmap;

  struct Human {
    double position_noise_m = 0;
    double heading_noise_rad = 0;
    bool use_gyro = false;
    double yaw_rate_noise_radps = 0;
    double accel_noise_mps2 = 0;
    double yaw_accel_noise_radps2 = 0;
    double prediction_time_constant_s = 0;
    double prediction_turn_time_constant_s = 0;
    double prediction_heading_turn_time_constant_s = 0;
    double gate_probability = 0;
    int64_t reset_after_rejects = 0;
    int64_t reset_after_gap_ms = 0;
  } human;

  struct Realtime {
    bool enable = true;    // try mlockall + SCHED_FIFO threads
    bool require = false;  // refuse to start if not permitted
  } realtime;

  struct Logging {
    std::string level;
    double summary_period_s = 0;
    int64_t warning_interval_ms = 0;
  } logging;

  struct Supervisor {
    int64_t arming_time_ms = 0;
    int64_t resume_after_ms = 0;
    int64_t tracker_timeout_ms = 0;
    int64_t tracker_confidence_recover_ms = 0;
    double person_max_distance_m = 0;
    int64_t lidar_timeout_ms = 0;
    int64_t costmap_max_age_ms = 0;
    int64_t base_feedback_timeout_ms = 0;
    int64_t control_stall_timeout_ms = 0;
    int64_t control_overruns_to_hold = 0;
    int64_t control_overrun_window_ms = 0;
    double stop_linear_decel_mps2 = 0;
    double stop_angular_decel_radps2 = 0;
    int64_t stop_max_time_ms = 0;
  } supervisor;

  struct Limits {
    double vx_max_mps = 0;
    double vy_max_mps = 0;
    double wz_max_radps = 0;
    double linear_accel_max_mps2 = 0;
    double angular_accel_max_radps2 = 0;
  } limits;

  struct InteractiveSpace {
    int64_t points = 0;
    double ellipse_a_m = 0;
    double ellipse_b_m = 0;
    double cost_threshold = 0;
    bool speed_standoff = false;
    double speed_standoff_filter_s = 0;
    double speed_standoff_max_m = 0;
  } interactive_space;

  struct Objective {
    double alpha = 0;
    double beta = 0;
    double gamma = 0;
    double delta = 0;
    double switch_cost = 0;
    double slew_points_per_s = 0;
    double turn_inside = 0;
  } objective;

  struct Policy {
    std::string file;      // empty: the objective argmin selects
    std::string selector;  // auto, objective, fixed_behind, fixed_side
    double hold_last_point_ms = 0;
  } policy;

  struct Control {
    std::string controller;  // mppi_cbf, pid_follower
  } control;

  struct Mppi {
    int64_t horizon_steps = 0;
    double step_s = 0;
    int64_t samples = 0;
    double lambda = 0;
    int64_t min_effective_samples = 0;
    double q_x = 0;
    double q_y = 0;
    double q_theta = 0;
    std::string tracking_frame;  // goal, robot
    double collision_cost = 0;
    double contact_cost = 0;  // 0: off
    bool guide_samples = false;
    bool path_guide = false;
    bool orbit_guide = false;
    double noise_vx_mps = 0;
    double noise_vy_mps = 0;
    double noise_wz_radps = 0;
    double terminal_weight = 0;
    double reverse_speed_max_mps = 0;
    double guide_heading_gain_per_s = 0;
    int64_t threads = 0;
    int64_t seed = 0;
  } mppi;

  struct Dcbf {
    double delta = 0;
    double c_safe = 0;
  } dcbf;

  struct ClosingSpeed {
    double robot_decel_mps2 = 0;  // 0: off
    double person_accel_mps2 = 0;
    double reaction_time_s = 0;
    double margin_m = 0;
    double person_radius_m = 0;
  } closing_speed;

  struct ObstacleSpeed {
    double robot_decel_mps2 = 0;  // 0: off
    double reaction_time_s = 0;
    double margin_m = 0;
    double settled_s = 0;
  } obstacle_speed;
};

}  // namespace firmware
