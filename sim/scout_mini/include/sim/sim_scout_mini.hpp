#pragma once
// A simulated AgileX Scout Mini Omni that behaves on the CAN bus like the real base: starts in
// standby, accepts motion only after 0x421 = CAN mode, stops by itself 500 ms after the last
// 0x111, honours acceleration limits, and publishes its feedback at the real periods. Faults can
// be injected. Time is passed in (step()); it only sees the bus, never the driver.
#include <array>
#include <cstdint>
#include <deque>
#include <random>

#include "hal/can/can_bus.hpp"
#include "scout_mini/odometry.hpp"
#include "scout_mini/scout_codec.hpp"

namespace sim {

struct SimScoutConfig {
  double linear_accel_mps2 = 1.5;
  double angular_accel_radps2 = 3.0;
  hal::Nanos command_timeout = std::chrono::milliseconds(500);
  // The motor controllers' reaction: a 0x111 takes effect this long after it arrived.
  hal::Nanos command_latency{0};
  // Reported (0x221) velocity = true velocity x (1 + N(0, this)): wheel slip and encoder error,
  // which the daemon's odometry integrates into drift. Zero while standing (encoders read 0).
  double feedback_noise_rel = 0.0;
  uint32_t seed = 1;
  double battery_v = 25.2;
  double track_m = 0.45;                              // wheel track, for the 0x311 wheel odometers
  scout_mini::MotionLimits limits{3.0, 2.0, 2.5235};  // firmware limits
  scout_mini::VersionReply version{0x0102, 0x0103, 0x0205, 0x0104};
};

class SimScoutMini {
 public:
  SimScoutMini(hal::CanBus& bus, const SimScoutConfig& config = {});

  // Processes received frames, advances the kinematics to `now`, sends the feedback that is due.
  void step(hal::Nanos now);

  // Fault injection.
  void set_estop(bool pressed);
  void set_rc_takeover(bool active);   // a person takes the remote (mode 3)
  void set_under_voltage(bool low);    // battery under-voltage fault: motors cut
  void inject_motor_fault(int motor);  // driver over-current, latched until 0x441
  void set_feedback_silent(bool silent);
  void power_cycle();  // back to standby, everything reset but the pose

  // Ground truth.
  [[nodiscard]] scout_mini::ControlMode mode() const { return mode_; }
  [[nodiscard]] const scout_mini::MotionState& velocity() const { return velocity_; }
  [[nodiscard]] const scout_mini::Pose2D& pose() const { return pose_; }
  [[nodiscard]] uint16_t fault_word() const;
  [[nodiscard]] uint64_t commands_accepted() const { return commands_accepted_; }
  [[nodiscard]] uint64_t commands_ignored() const { return commands_ignored_; }

 private:
  void receive(hal::Nanos now);
  void advance(hal::Nanos now);
  void publish(hal::Nanos now);
  bool can_drive() const;

  hal::CanBus& bus_;
  SimScoutConfig config_;
  scout_mini::ControlMode mode_ = scout_mini::ControlMode::kStandby;
  scout_mini::MotionState target_{0, 0, 0};
  struct Pending {
    hal::Nanos apply_at;
    scout_mini::MotionState target;
  };
  std::deque<Pending> pending_;  // received commands not yet in effect (command_latency)
  std::mt19937 rng_;
  std::normal_distribution<double> unit_{0.0, 1.0};
  scout_mini::MotionState velocity_{0, 0, 0};
  scout_mini::Pose2D pose_;
  double left_mm_ = 0, right_mm_ = 0;
  hal::Nanos last_command_{0};
  bool has_command_ = false;
  bool timed_out_ = false;
  hal::Nanos last_step_{0};
  bool started_ = false;
  bool estop_ = false;
  bool rc_ = false;
  bool under_voltage_ = false;
  std::array<bool, 4> motor_fault_{};
  bool silent_ = false;
  hal::Nanos next_fast_{0};  // 20 ms group
  hal::Nanos next_slow_{0};  // 100 ms group
  uint8_t count_ = 0;
  scout_mini::LightState lights_{false, 0, 0, 0, 0};
  uint64_t commands_accepted_ = 0;
  uint64_t commands_ignored_ = 0;
};

}  // namespace sim
