#pragma once
// Pedestrians that walk to their goals and avoid each other, the person, the robot and the walls:
// the social-force model of Helbing & Molnar (1995) with the common parameter set
// (reference/evaluation.md): relaxation to the desired velocity in tau, an elliptical repulsive
// potential V0 exp(-b / sigma) between people (b from the other's step s = |v| dt and the distance
// between the bodies' surfaces, so the robot and wide people are avoided at their size), a wall
// potential U0 exp(-d / R), a field of view of +-100 degrees outside of which forces count half,
// and a speed cap at 1.3x the desired speed. Integrated with semi-implicit Euler.
#include <cstdint>
#include <span>
#include <vector>

#include "sim/static_world.hpp"

namespace sim {

struct SocialForceParams {
  double tau_s = 0.5;
  double v0_m2ps2 = 2.1;  // person-person potential strength
  double sigma_m = 0.3;
  double u0_m2ps2 = 10.0;  // wall potential strength
  double wall_r_m = 0.2;
  double step_width_s = 2.0;  // dt of the elliptical potential (Helbing & Molnar)
  double fov_half_rad = 100.0 * 3.14159265358979 / 180.0;
  double outside_fov_weight = 0.5;
  double max_speed_factor = 1.3;
  double goal_radius_m = 0.5;
  double interaction_range_m = 5.0;  // farther people and walls are ignored
};

struct Pedestrian {
  Point2 position;
  Point2 velocity;
  double desired_speed_mps = 1.2;
  double radius_m = 0.25;
  std::vector<Point2> goals;  // walked in order
  bool loop = false;          // back to the first goal after the last
  size_t next_goal = 0;
  [[nodiscard]] bool arrived() const { return next_goal >= goals.size(); }
};

// Someone the crowd avoids but does not move: the followed person, the robot, replayed people.
struct MovingBody {
  Point2 position;
  Point2 velocity;
  double radius_m = 0.3;
};

class Crowd {
 public:
  explicit Crowd(SocialForceParams params = {}) : params_(params) {}

  void add(Pedestrian p) { people_.push_back(std::move(p)); }
  // Advances every pedestrian by dt_s.
  void step(double dt_s, const StaticWorld& world, std::span<const MovingBody> others);

  [[nodiscard]] const std::vector<Pedestrian>& people() const { return people_; }
  [[nodiscard]] const SocialForceParams& params() const { return params_; }

  // The force on `self` from a person at `other` (exposed for the unit tests).
  [[nodiscard]] Point2 person_force(const Point2& self, double self_radius_m,
                                    const Point2& desired_dir, const MovingBody& other) const;
  [[nodiscard]] Point2 wall_force(const Point2& self, const Point2& desired_dir,
                                  const StaticWorld& world) const;

 private:
  [[nodiscard]] double fov_weight(const Point2& desired_dir, const Point2& force) const;

  SocialForceParams params_;
  std::vector<Pedestrian> people_;
  std::vector<MovingBody> bodies_;  // scratch
  std::vector<Point2> accel_;       // scratch
};

}  // namespace sim
