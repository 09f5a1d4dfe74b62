#pragma once
// The simulated world around the daemon: a scenario (walls, the person, pedestrians), the
// simulated Scout Mini on a CAN bus, the simulated Amfitrack sensing the person relative to the
// robot, and the simulated VLP-16 ray casting the world. It hands the daemon the device ends
// (a CAN bus, an Amfiprot packet link, a datagram source): the daemon's drivers decode the same
// bytes as on the robot. Time is passed in (step), so it runs on the simulated clock (fast,
// deterministic) or on the real one (a thread calling step at its own rate).
#include <memory>
#include <optional>
#include <vector>

#include "amfitrack/packet_link.hpp"
#include "amfitrack/person_frame.hpp"
#include "hal/can/virtual_can.hpp"
#include "hal/net/datagram_queue.hpp"
#include "sim/scenario.hpp"
#include "sim/sim_amfitrack.hpp"
#include "sim/sim_scout_mini.hpp"
#include "sim/sim_vlp16.hpp"

namespace sim {

struct SimWorldConfig {
  double step_s = 0.005;  // world physics and device emulation step (200 Hz)
  SimScoutConfig base;
  SimAmfitrackConfig tracker;
  SimVlp16Config lidar;
  amfitrack::TrackerExtrinsics tracker_extrinsics;  // the daemon's tracker.* keys
  double sensor_height_m = 1.0;                     // the worn sensor above the ground
  // The worn sensor turns with the torso, which sways about the way the person walks (about
  // +-4 degrees at the belt or chest, one cycle per stride): its yaw is their heading plus
  // person_sway_rad sin(phase), the phase advancing 2 pi per person_stride_m walked, and its
  // gyro reads the sway's rate too. The metrics' person is the walking heading. 0: no sway.
  double person_sway_rad = 0.0;
  double person_stride_m = 1.4;
  // The robot's footprint in base_link (collisions): the daemon's costmap.footprint_* keys.
  double footprint_x_min_m = -0.35, footprint_x_max_m = 0.35;
  double footprint_y_min_m = -0.30, footprint_y_max_m = 0.30;
  double robot_avoid_radius_m = 0.45;  // how pedestrians see the robot (social force)
  // The followed person walks their script but does not walk into the robot (as nobody walks
  // into a robot standing in their way): a step that would bring them closer than
  // person_contact_margin_m to its footprint keeps only its part along the footprint (they slide
  // past it), and once clear they drift back onto their path at person_return_mps. A contact the
  // robot causes by driving into the person still counts. Off: the person walks through it.
  bool person_avoids_robot = true;
  // Recorded pedestrians (Scenario::replayed) likewise walk their recording but not into the
  // robot (evaluation.md: pedestrians react to the robot), with the same margin and return
  // speed; one first seen where the robot stands appears just clear of it. Off: they walk
  // through it and appear where recorded (the recorded tables up to the thirty-seventh session).
  bool replayed_avoid_robot = true;
  double person_contact_margin_m = 0.05;
  double person_return_mps = 0.5;
};

// Everything true at one instant, for metrics, reports and pictures.
struct WorldSample {
  double t_s = 0;
  core::Pose2 robot;
  core::Pose2 person;
  std::vector<Point2> pedestrians;  // social-force and replayed
};

class SimWorld {
 public:
  SimWorld(Scenario scenario, const SimWorldConfig& config, hal::Clock& clock);
  ~SimWorld();
  SimWorld(const SimWorld&) = delete;
  SimWorld& operator=(const SimWorld&) = delete;

  // The daemon's ends of the three devices (each may be taken once).
  std::unique_ptr<hal::CanBus> take_base_bus();
  // The tracker as on its UART: COBS-framed Amfiprot bytes over a local stream socket, read by
  // the daemon's serial link (framing, CRC and all). Unix sockets deliver within the write, so
  // the simulated clock stays deterministic.
  std::unique_ptr<amfitrack::PacketLink> take_tracker_link();
  std::unique_ptr<hal::DatagramSource> take_lidar_source();
  // Another endpoint on the base's CAN bus that sees every frame (captures, tests).
  std::unique_ptr<hal::VirtualCanBus> open_can_sniffer();

  // Advances everything to `now` (in steps of config.step_s) and emits the devices' traffic.
  void step(hal::Nanos now);

  // Ground truth, world frame.
  [[nodiscard]] core::Pose2 robot_pose() const;
  [[nodiscard]] core::Pose2 person_pose() const { return person_; }
  [[nodiscard]] Point2 person_velocity() const { return person_velocity_; }
  [[nodiscard]] std::vector<Point2> pedestrian_positions() const;
  [[nodiscard]] double time_s() const { return t_s_; }
  [[nodiscard]] const Scenario& scenario() const { return scenario_; }
  [[nodiscard]] const SimWorldConfig& config() const { return config_; }

  // Distances from the robot's footprint (0 = touching or overlapping).
  [[nodiscard]] double footprint_clearance_static() const;
  [[nodiscard]] double footprint_clearance_people() const;  // pedestrians and the person

  // The devices, for fault injection in tests.
  SimScoutMini& base() { return *base_; }
  SimAmfitrack& tracker() { return tracker_; }
  [[nodiscard]] const SimVlp16& lidar() const { return lidar_; }
  // The VLP-16's packets stop (cable, power) while set.
  void set_lidar_silent(bool silent) { lidar_silent_ = silent; }

 private:
  // A walker on a scripted path (the person, a recorded pedestrian).
  struct ScriptedWalker {
    Point2 at;
    Point2 offset;  // where they are, minus where their script has them
    Point2 velocity;
  };
  void advance(double t_s);
  void move_person(double t_s, double dt_s);
  void move_replayed(double t_s, double dt_s);
  // One step of `w` toward `scripted` that does not walk into the robot (SimWorldConfig::
  // person_avoids_robot); `scripted` carries the way they face.
  [[nodiscard]] ScriptedWalker step_clear_of_robot(const ScriptedWalker& w,
                                                   const core::Pose2& scripted, double radius_m,
                                                   double dt_s) const;
  // The footprint's outward normal at `p` (world frame; from its centre when inside it).
  [[nodiscard]] Point2 footprint_normal(const Point2& p) const;
  // `p` moved out along that normal until a body of `radius_m` there keeps the contact margin:
  // where a recorded pedestrian first seen at the robot is (they walked round it unseen, and
  // return to their recording as from any detour).
  [[nodiscard]] Point2 clear_of_robot(Point2 p, double radius_m) const;
  [[nodiscard]] double sway_phase_rate_radps() const;  // 2 pi per stride at the person's pace
  void update_tracker_pose();
  [[nodiscard]] double footprint_distance(const Point2& p) const;  // point to footprint (world)
  [[nodiscard]] core::Pose2 robot_at(hal::Nanos t) const;

  Scenario scenario_;
  SimWorldConfig config_;
  hal::Clock& clock_;
  std::string can_network_;
  std::unique_ptr<hal::VirtualCanBus> base_bus_;    // the base's end
  std::unique_ptr<hal::VirtualCanBus> daemon_bus_;  // until taken
  std::unique_ptr<SimScoutMini> base_;
  SimAmfitrack tracker_;
  int tracker_fd_ = -1;  // the device's end of the tracker's byte stream
  SimVlp16 lidar_;
  std::shared_ptr<hal::DatagramQueue> lidar_queue_;
  Crowd crowd_;
  Eigen::Matrix3d r_base_source_;
  Eigen::Vector3d t_base_source_;
  Eigen::Matrix3d r_body_sensor_;
  double sway_phase_rad_ = 0;  // SimWorldConfig::person_sway_rad's, advanced by distance walked

  bool lidar_silent_ = false;
  bool started_ = false;
  double t_s_ = 0;
  hal::Nanos last_step_{0};
  core::Pose2 prev_robot_;  // at the previous step (the lidar interpolates within a step)
  hal::Nanos prev_robot_time_{0};
  core::Pose2 person_;
  Point2 person_velocity_;
  Point2 person_offset_;  // where the person is, minus where their script has them
  // Scenario::replayed's walkers, one each; none while outside their recording's times.
  std::vector<std::optional<ScriptedWalker>> replayed_;
  std::vector<Cylinder> cylinders_;  // scratch
  std::vector<MovingBody> bodies_;   // scratch
};

}  // namespace sim
