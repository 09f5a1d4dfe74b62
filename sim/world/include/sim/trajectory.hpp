#pragma once
// A walked path as timed samples (world frame), interpolated: how the simulated person moves
// (a scripted waypoint walk, or one person of a recorded dataset) and how recorded pedestrians
// are replayed. Before its first sample an agent stands at the first one; after its last, at
// the last one.
#include <vector>

#include "core/geometry/pose2.hpp"

namespace sim {

struct TimedPose {
  double t_s = 0;
  core::Pose2 pose;  // heading = walking direction
};

class Trajectory {
 public:
  Trajectory() = default;
  explicit Trajectory(std::vector<TimedPose> samples) : samples_(std::move(samples)) {}

  [[nodiscard]] core::Pose2 pose_at(double t_s) const;
  [[nodiscard]] core::Point2 velocity_at(double t_s) const;  // m/s, world frame
  // rad/s (+ left) of the sample step at t_s: how fast the walker turns there. pose_at holds a
  // step's heading and turns at its end (a staircase); this is the turn the steps are made of.
  [[nodiscard]] double turn_rate_at(double t_s) const;
  [[nodiscard]] double start_s() const { return samples_.empty() ? 0.0 : samples_.front().t_s; }
  [[nodiscard]] double end_s() const { return samples_.empty() ? 0.0 : samples_.back().t_s; }
  [[nodiscard]] bool empty() const { return samples_.empty(); }
  [[nodiscard]] const std::vector<TimedPose>& samples() const { return samples_; }

 private:
  // The sample step [i, i + 1] that holds t_s (samples_[i].t_s <= t_s < samples_[i + 1].t_s);
  // for t_s within [first, last) only.
  [[nodiscard]] size_t step_at(double t_s) const;

  std::vector<TimedPose> samples_;
};

// A waypoint walk: legs at their own speeds, optional pauses, and corners taken the way a
// walking person can: on an arc no tighter than their lateral acceleration and turn rate allow
// (a 90-degree corner at 1.4 m/s takes ~0.7 s, about one stride), slowing down only where the
// legs are too short for that arc. A person who pauses at a waypoint turns there on the spot.
// `corner` with zero limits gives the old sudden turns (the walker faces the next leg at once).
struct Waypoint {
  core::Point2 p;
  double speed_mps = 1.0;  // on the leg that ends here
  double pause_s = 0;      // standing here before the next leg
};
struct CornerLimits {
  double lateral_accel_mps2 = 3.0;  // v^2 / r while turning
  double turn_rate_radps = 3.0;     // v / r: ~170 deg/s, a quick turn in one step
  // > 0: the walker speeds up from standing and slows down to standing (at a pause and at the
  // end) this evenly; 0: at once (the benchmark worlds' walks up to the twenty-third session;
  // they ease at 3 m/s^2 since, dead ends at 1: sim/scenario.hpp). Turns taken on
  // the spot while paused stay sudden.
  double start_stop_accel_mps2 = 0.0;
  // A corner tighter than the walking speed allows (a turn back) is walked slower: the walker
  // slows down into it and speeds up out of it this evenly (3 m/s^2: a brisk stop, the person's
  // acceleration the daemon's closing-speed rule assumes). 0: at once, as the walks of the
  // benchmark up to the twenty-first session (from 1.4 m/s to a near standstill in one 50 ms
  // step, 10+ m/s^2, and back at the robot as fast: docs/eval/SESSIONS.md, twenty-second session).
  double speed_change_accel_mps2 = 3.0;
};
// Sampled every `step_s`, starting at `start_s` (standing at the first waypoint until then).
Trajectory walk(const std::vector<Waypoint>& waypoints, double start_s = 0.0, double step_s = 0.05,
                const CornerLimits& corner = {});

// Recorded positions (a few per second) as the person walked between them: a curve through
// every observation whose velocity changes smoothly (cubic Hermite pieces, the velocity at each
// observation from its neighbours), sampled every `step_s` from the first observation to the
// last, headings from its motion (set_headings_from_motion). Linear interpolation of a 2.5 Hz
// track makes the walker's velocity and heading jump at every frame (0.4 s), which no walker
// does and which the daemon would chase. A person who stops has no velocity where they stop,
// so the curve does not carry them past it and back. Under two observations: as given.
Trajectory smooth_track(const Trajectory& observed, double step_s = 0.05);

// Path length walked (m).
double path_length(const Trajectory& t);
// Headings of position samples from their motion (kept while standing: below 0.2 m/s).
void set_headings_from_motion(std::vector<TimedPose>& samples);

}  // namespace sim
