#include "schema.hpp"

#include <limits>

namespace firmware::config_schema {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

#define FIELD(path) [](DaemonConfig& c) -> FieldRef { return &c.path; }

std::vector<FieldSpec> build() {
  return {
      // --- devices -------------------------------------------------------------------------
      {"devices.tracker", "uri",
       "Amfitrack Gen 3 link: `hid:auto` (first sensor/source on USB), `hid:<hidraw path or "
       "serial>`, `serial:<port>[@baud]`, `sim` (built-in simulated world) or `none`.",
       FIELD(devices.tracker), 0, 0, {"hid:", "serial:", "sim", "none"}},
      {"devices.lidar", "uri",
       "VLP-16 data stream: `udp:<bind address>:<port>` (port 2368 on the robot), `sim` or `none`.",
       FIELD(devices.lidar), 0, 0, {"udp:", "sim", "none"}},
      {"devices.base", "uri",
       "Scout Mini CAN link: `socketcan:<ifname>` (can0), `slcan:<serial port>`, "
       "`virtual:<bus name>` (in-process), `sim` or `none`.",
       FIELD(devices.base), 0, 0, {"socketcan:", "slcan:", "virtual:", "sim", "none"}},
      // --- realtime ------------------------------------------------------------------------
      {"realtime.enable", "bool",
       "Lock memory (mlockall) and run the rate-group threads SCHED_FIFO at the task table's "
       "priorities. Without permission a warning is logged and the daemon runs normally.",
       FIELD(realtime.enable), 0, 0, {}},
      {"realtime.require", "bool",
       "Refuse to start when real-time scheduling or memory locking is not permitted.",
       FIELD(realtime.require), 0, 0, {}},
      // --- logging -------------------------------------------------------------------------
      {"logging.level", "level", "Minimum level logged: trace, debug, info, warn, error.",
       FIELD(logging.level), 0, 0, {"trace", "debug", "info", "warn", "error"}},
      {"logging.summary_period_s", "s",
       "Period of the one-line summary log (state, reason, task rates, jitter, overruns).",
       FIELD(logging.summary_period_s), 1.0, 3600.0, {}},
      {"logging.warning_interval_ms", "ms",
       "A repeated warning is logged at most once per interval; the suppressed ones are counted.",
       FIELD(logging.warning_interval_ms), 10, 600000, {}},
      // --- supervisor ----------------------------------------------------------------------
      {"supervisor.arming_time_ms", "ms",
       "After start-up (or a fault clear) every input must be healthy this long before ACTIVE.",
       FIELD(supervisor.arming_time_ms), 0, 60000, {}},
      {"supervisor.resume_after_ms", "ms",
       "A HOLD cause must stay clear this long before motion resumes (hysteresis).",
       FIELD(supervisor.resume_after_ms), 0, 60000, {}},
      {"supervisor.tracker_timeout_ms", "ms",
       "Tracker data older than this is 'tracker silent' (120 Hz nominal: 8.3 ms per frame).",
       FIELD(supervisor.tracker_timeout_ms), 10, 5000, {}},
      {"supervisor.tracker_confidence_recover_ms", "ms",
       "After low tracker confidence, confidence must be GOOD this long before motion resumes.",
       FIELD(supervisor.tracker_confidence_recover_ms), 0, 60000, {}},
      {"supervisor.person_max_distance_m", "m",
       "The person further than this from the robot is 'person lost'.",
       FIELD(supervisor.person_max_distance_m), 0.5, 20.0, {}},
      {"supervisor.lidar_timeout_ms", "ms",
       "No decoded lidar packet for this long is 'lidar silent' (packets arrive every 1.3 ms).",
       FIELD(supervisor.lidar_timeout_ms), 10, 5000, {}},
      {"supervisor.costmap_max_age_ms", "ms",
       "A costmap built from data older than this is 'costmap stale' (10 Hz scans).",
       FIELD(supervisor.costmap_max_age_ms), 100, 5000, {}},
      {"supervisor.base_feedback_timeout_ms", "ms",
       "No Scout Mini feedback frame for this long is 'base feedback silent' (0x221 every 20 ms).",
       FIELD(supervisor.base_feedback_timeout_ms), 20, 5000, {}},
      {"supervisor.control_stall_timeout_ms", "ms",
       "The control task not completing a run for this long is a latched 'control stalled' fault "
       "and stops the systemd watchdog pings.",
       FIELD(supervisor.control_stall_timeout_ms), 20, 5000, {}},
      {"supervisor.stop_linear_decel_mps2", "m/s^2",
       "Deceleration of a controlled stop (planar speed), within the base's limits.",
       FIELD(supervisor.stop_linear_decel_mps2), 0.1, 10.0, {}},
      {"supervisor.stop_angular_decel_radps2", "rad/s^2",
       "Deceleration of the yaw rate during a controlled stop.",
       FIELD(supervisor.stop_angular_decel_radps2), 0.1, 20.0, {}},
      {"supervisor.stop_max_time_ms", "ms",
       "Upper bound of a controlled stop: the command is exactly zero this long after motion "
       "stopped being allowed, whatever the deceleration left.",
       FIELD(supervisor.stop_max_time_ms), 0, 5000, {}},
      // --- limits --------------------------------------------------------------------------
      {"limits.vx_max_mps", "m/s", "Forward/backward speed limit sent to the base (SDK max 3.0).",
       FIELD(limits.vx_max_mps), 0.0, 3.0, {}},
      {"limits.vy_max_mps", "m/s", "Lateral speed limit (mecanum; SDK max 2.0).",
       FIELD(limits.vy_max_mps), 0.0, 2.0, {}},
      {"limits.wz_max_radps", "rad/s", "Yaw rate limit (SDK max 2.5235).",
       FIELD(limits.wz_max_radps), 0.0, 2.5235, {}},
      {"limits.linear_accel_max_mps2", "m/s^2", "Acceleration limit applied to commands.",
       FIELD(limits.linear_accel_max_mps2), 0.1, 10.0, {}},
      {"limits.angular_accel_max_radps2", "rad/s^2", "Yaw acceleration limit applied to commands.",
       FIELD(limits.angular_accel_max_radps2), 0.1, 20.0, {}},
      // --- the paper's method (DESIGN.md section 6) ---------------------------------------
      {"interactive_space.points", "count",
       "n: candidate companion points on the ellipse around the person (paper: 64). Also the "
       "policy's action count: a policy file must match it.",
       FIELD(interactive_space.points), 4, 1024, {}},
      {"interactive_space.ellipse_a_m", "m",
       "a: semi-axis of the interactive-space ellipse along the person's heading (paper: 1.0).",
       FIELD(interactive_space.ellipse_a_m), 0.3, 5.0, {}},
      {"interactive_space.ellipse_b_m", "m",
       "b: lateral semi-axis of the ellipse (paper: 0.7). Also the DCBF ellipse.",
       FIELD(interactive_space.ellipse_b_m), 0.3, 5.0, {}},
      {"interactive_space.cost_threshold", "cost (0-100)",
       "R: a point whose costmap cost is >= R is not collision-free (paper: 30). Costmap scale: "
       "0 free, 100 lethal (robot centre would overlap an obstacle), exponential decay between.",
       FIELD(interactive_space.cost_threshold), 1.0, 100.0, {}},
      {"objective.alpha", "1/m",
       "alpha: weight of the distance from a candidate to the person in G (not given in the "
       "paper; chosen).",
       FIELD(objective.alpha), 0.0, 1000.0, {}},
      {"objective.beta", "1/m",
       "beta: weight of the distance from a candidate to the robot in G (not given; chosen).",
       FIELD(objective.beta), 0.0, 1000.0, {}},
      {"objective.gamma", "1/cost",
       "gamma: weight of the costmap cost of a candidate in G (not given; chosen).",
       FIELD(objective.gamma), 0.0, 1000.0, {}},
      {"mppi.horizon_steps", "count", "K: prediction steps (paper: 100).",
       FIELD(mppi.horizon_steps), 1, 1000, {}},
      {"mppi.step_s", "s", "Delta t: prediction step (paper: 0.1).", FIELD(mppi.step_s), 0.001,
       1.0, {}},
      {"mppi.samples", "count", "M: sampled control sequences per update (paper: 2000).",
       FIELD(mppi.samples), 1, 100000, {}},
      {"mppi.lambda", "-", "lambda: temperature of the importance weights (paper: 1.0).",
       FIELD(mppi.lambda), 1e-6, 1e6, {}},
      {"mppi.q_x", "1/m^2", "c_x: weight of the x tracking error in Q (paper: 50).",
       FIELD(mppi.q_x), 0.0, 1e6, {}},
      {"mppi.q_y", "1/m^2", "c_y: weight of the y tracking error in Q (paper: 10).",
       FIELD(mppi.q_y), 0.0, 1e6, {}},
      {"mppi.q_theta", "1/rad^2", "c_theta: weight of the heading error in Q (paper: 20).",
       FIELD(mppi.q_theta), 0.0, 1e6, {}},
      {"mppi.collision_cost", "-",
       "c_collision: cost of a predicted state whose costmap cost is >= R (paper: 1000).",
       FIELD(mppi.collision_cost), 0.0, 1e9, {}},
      {"mppi.noise_vx_mps", "m/s", "Sigma: std-dev of the sampled forward-velocity noise.",
       FIELD(mppi.noise_vx_mps), 0.0, 5.0, {}},
      {"mppi.noise_vy_mps", "m/s", "Sigma: std-dev of the sampled lateral-velocity noise.",
       FIELD(mppi.noise_vy_mps), 0.0, 5.0, {}},
      {"mppi.noise_wz_radps", "rad/s", "Sigma: std-dev of the sampled yaw-rate noise.",
       FIELD(mppi.noise_wz_radps), 0.0, 5.0, {}},
      {"dcbf.delta", "-", "delta: DCBF decay rate, h_{k+1} >= (1 - delta) h_k (paper: 0.5).",
       FIELD(dcbf.delta), 1e-6, 1.0, {}},
      {"dcbf.c_safe", "-", "c_safe: weight of a DCBF violation in the MPPI cost (paper: 5000).",
       FIELD(dcbf.c_safe), 0.0, 1e9, {}},
  };
}

#undef FIELD

}  // namespace

const std::vector<FieldSpec>& fields() {
  static const std::vector<FieldSpec> kFields = build();
  return kFields;
}

}  // namespace firmware::config_schema
