#pragma once
// A simulated Amfitrack Gen 3 (source on the robot + sensor worn by the person) that speaks
// Amfiprot: it emits the sensor's 0x1A frames at its rate through the source's link (header
// source = the sensor's TX id), answers RequestDeviceID / firmware / name requests for both
// devices, and can be scripted: quality drops, lost tracking, B-field states, dropped frames,
// silence. Time is passed in (step), so it runs on the simulated clock or the real one.
//
// Transports: host_link() is an in-process amfitrack::PacketLink (thread-safe), and
// pump_cobs() moves the same packets as a COBS byte stream over a file descriptor (the master
// side of a pseudo-terminal), so the daemon's and the tools' serial path is exercised for real.
#include <array>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <random>
#include <string>

#include "amfitrack/amfiprot_codec.hpp"
#include "amfitrack/packet_link.hpp"
#include "hal/clock.hpp"

namespace sim {

struct SimAmfitrackConfig {
  uint8_t source_tx_id = 1;
  uint8_t sensor_tx_id = 2;
  double rate_hz = 120.0;
  double position_noise_m = 0.0;  // 1-sigma per axis, white
  double heading_noise_rad = 0.0;
  // The sensor's IMU: a constant bias and white noise (1-sigma) on each gyro axis. Drawn from
  // a generator of its own, so turning it on leaves the pose noise's sequence as it was.
  std::array<double, 3> gyro_bias_dps{0, 0, 0};
  double gyro_noise_dps = 0.0;
  uint32_t seed = 1;
  std::string source_name = "AMFITRACK SOURCE";
  std::string sensor_name = "AMFITRACK SENSOR";
  std::array<uint32_t, 4> firmware{0, 6, 2, 0};
};

class SimAmfitrack {
 public:
  explicit SimAmfitrack(const SimAmfitrackConfig& config = {});

  // The person's sensor, in the SOURCE frame: position and yaw about the source's z (the sensor
  // upright), or a full orientation.
  void set_sensor_pose(double x_m, double y_m, double z_m, double yaw_rad);
  void set_sensor_pose(const std::array<double, 3>& position_m,
                       const std::array<double, 4>& quaternion_xyzw);
  // The sensor's angular velocity in its own frame (what its gyro measures), degrees/s.
  void set_gyro_dps(const std::array<double, 3>& gyro) { gyro_dps_ = gyro; }
  void set_quality(uint8_t raw) { quality_ = raw; }
  void set_pose_state(uint8_t raw) { pose_state_ = raw; }  // 1 tracking, 0 none, 2 uncertain
  void set_bfield(amfitrack::BFieldStatus s) { bfield_ = s; }
  void set_source_connected(bool c) { source_connected_ = c; }
  void drop_frames(uint32_t n) { drop_ += n; }  // the next n frame ids never arrive
  void set_silent(bool s) { silent_ = s; }      // no frames (unplugged sensor, RF loss)

  // Emits every frame due up to `now` and answers the host's requests.
  void step(hal::Nanos now);

  // In-process host end (for the daemon in the simulated world and tests). One per device.
  std::unique_ptr<amfitrack::PacketLink> host_link();
  // Moves packets over a non-blocking fd as COBS frames (device -> host) and decodes the host's
  // requests from it. Call after step(). Returns false when the fd failed.
  bool pump_cobs(int fd);

  [[nodiscard]] uint64_t frames_sent() const { return frames_sent_; }
  [[nodiscard]] uint64_t requests_received() const { return requests_; }
  [[nodiscard]] uint32_t next_frame_id() const { return frame_id_; }

 private:
  struct Queues {
    std::mutex mutex;
    std::deque<amfitrack::Packet> to_host;
    std::deque<amfitrack::Packet> from_host;
  };
  void emit(amfitrack::Packet p);
  void answer(const amfitrack::Packet& request);
  [[nodiscard]] amfitrack::SensorMeasurement measurement();

  SimAmfitrackConfig config_;
  std::shared_ptr<Queues> q_;
  amfitrack::CobsStreamDecoder cobs_in_;
  std::vector<uint8_t> cobs_out_;
  std::mt19937 rng_;
  std::mt19937 gyro_rng_;
  std::normal_distribution<double> gyro_unit_{0.0, 1.0};  // its own: the draws come in pairs
  std::normal_distribution<double> unit_{0.0, 1.0};
  std::array<double, 3> position_m_{1.0, 0.0, 0.0};
  std::array<double, 4> quaternion_xyzw_{0, 0, 0, 1};
  std::array<double, 3> gyro_dps_{};
  uint8_t quality_ = 230;
  uint8_t pose_state_ = 1;
  amfitrack::BFieldStatus bfield_ = amfitrack::BFieldStatus::kTracking;
  bool source_connected_ = true;
  bool silent_ = false;
  uint32_t drop_ = 0;
  uint32_t frame_id_ = 1;
  uint8_t packet_number_ = 0;
  bool started_ = false;
  hal::Nanos next_frame_{0};
  uint64_t frames_sent_ = 0;
  uint64_t requests_ = 0;
};

}  // namespace sim
