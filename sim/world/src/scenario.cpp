#include "sim/scenario.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "sim/pedestrian_dataset.hpp"

namespace sim {

namespace {
constexpr double kTailS = 3.0;  // standing at the end, so the run ends at rest
constexpr CornerLimits kBuiltInWalk{.start_stop_accel_mps2 = kBuiltInStartStopAccelMps2};

Scenario base_scenario(const char* name, const char* description,
                       const std::vector<Waypoint>& walk_points,
                       const CornerLimits& corner = kBuiltInWalk) {
  Scenario s;
  s.name = name;
  s.description = description;
  s.person = walk(walk_points, kBuiltInStartDelayS, 0.05, corner);
  const core::Pose2 p0 = s.person.pose_at(0.0);
  s.robot_start = p0 * core::Pose2{-1.0, 0.0, 0.0};  // 1 m behind the person, same heading
  s.duration_s = s.person.end_s() + kTailS;
  return s;
}

Pedestrian walker(Point2 from, Point2 to, double speed) {
  Pedestrian p;
  p.position = from;
  p.desired_speed_mps = speed;
  p.goals = {to};
  return p;
}

Scenario open_space() {
  return base_scenario("open", "open space, rectangular walk with sharp turns",
                       {{{0, 0}}, {{8, 0}, 1.0}, {{8, 6}, 1.0}, {{0, 6}, 1.0}, {{0, 0.5}, 1.0}});
}

Scenario static_obstacle() {
  Scenario s = base_scenario("static_obstacle", "a static obstacle on one side of the walk",
                             {{{0, 0}}, {{16, 0}, 1.0}});
  // The robot starts behind-right; the obstacle on the right forces it to another side.
  s.robot_start = core::Pose2{-0.8, -0.6, 0.0};
  s.world.add_box({6.0, -3.0}, {10.0, -1.0});
  return s;
}

Scenario pedestrian_front_right() {
  Scenario s =
      base_scenario("pedestrian_front_right", "a pedestrian approaching from the front-right",
                    {{{0, 0}}, {{16, 0}, 1.0}});
  s.pedestrians.push_back(walker({16.0, -3.0}, {-4.0, 1.0}, 1.2));
  return s;
}

Scenario corridor() {
  Scenario s =
      base_scenario("corridor", "a corridor narrowing on both sides", {{{0, 0}}, {{18, 0}, 1.0}});
  // 5 m wide, narrowing to 2.4 m between x = 7 and 12, then wide again.
  for (double side : {-1.0, 1.0}) {
    s.world.add_wall({-3.0, 2.5 * side}, {5.0, 2.5 * side});
    s.world.add_wall({5.0, 2.5 * side}, {7.0, 1.2 * side});
    s.world.add_wall({7.0, 1.2 * side}, {12.0, 1.2 * side});
    s.world.add_wall({12.0, 1.2 * side}, {14.0, 2.5 * side});
    s.world.add_wall({14.0, 2.5 * side}, {21.0, 2.5 * side});
  }
  return s;
}

Scenario doorway() {
  Scenario s = base_scenario("doorway", "a doorway with a sudden turn behind it",
                             {{{0, 0}}, {{9.5, 0}, 1.0}, {{9.5, 6}, 1.0}});
  // A wall across the walk at x = 8 with a 2 m door; the person turns left right behind it.
  s.world.add_wall({8.0, -6.0}, {8.0, -1.0});
  s.world.add_wall({8.0, 1.0}, {8.0, 8.0});
  return s;
}

// When a walk along +x first reaches `x_m` (s; interpolated between its samples).
double time_reaching_x(const Trajectory& t, double x_m) {
  const std::vector<TimedPose>& p = t.samples();
  for (size_t i = 0; i < p.size(); ++i) {
    if (p[i].pose.x_m < x_m) continue;
    if (i == 0) return p[0].t_s;
    const double f = (x_m - p[i - 1].pose.x_m) / (p[i].pose.x_m - p[i - 1].pose.x_m);
    return p[i - 1].t_s + f * (p[i].t_s - p[i - 1].t_s);
  }
  return t.end_s();
}

Scenario crossing() {
  Scenario s = base_scenario("crossing", "three pedestrians crossing between robot and person",
                             {{{0, 0}}, {{16, 0}, 1.0}});
  // Each crosses the walk 0.6 m behind the person (between the person and the robot): at y = 0
  // when the person is at x + 0.6.
  for (double x : {5.0, 8.0, 11.0}) {
    const double t_cross = time_reaching_x(s.person, x + 0.6);
    const double speed = 1.2;
    const double y0 = -speed * t_cross;
    s.pedestrians.push_back(walker({x, y0}, {x, 8.0}, speed));
  }
  return s;
}

double uniform(std::mt19937& rng, double a, double b) {
  return std::uniform_real_distribution<double>(a, b)(rng);
}

// A corridor with a closed end (seeded: 2.0-2.6 m wide, 6-11 m long, 0.8-1.4 m/s, 0-2 s at the
// end): the person walks in, turns round at the end and walks out, then on in the open. Behind
// them is then where the robot cannot get without passing them in the corridor: the robot has
// to lead them out. People start and stop at 1 m/s^2 here (a sudden turn back into the robot
// at walking speed is not a thing people do, and no robot could brake for it).
Scenario dead_end(uint32_t seed) {
  std::mt19937 rng(seed);
  const double width_m = uniform(rng, 2.0, 2.6);
  const double length_m = uniform(rng, 6.0, 11.0);
  const double speed = uniform(rng, 0.8, 1.4);
  const double pause_s = uniform(rng, 0.0, 2.0);
  const double out_turn = uniform(rng, -1.75, 1.75);  // where they go once out
  constexpr double kEntryM = 2.0;                     // the corridor's mouth, from the start
  const double end_x = kEntryM + length_m;
  // They turn 0.6 m before the end wall, walk back out to 0.5-2 m short of where they started
  // (2.5-4 m past the mouth), and on 4-6 m in a seeded direction.
  const double back_x = -uniform(rng, 0.5, 2.0);
  const double on_m = uniform(rng, 4.0, 6.0);
  Scenario s =
      base_scenario("dead_end", "a corridor with a closed end: the person turns back",
                    {{{0, 0}},
                     {{end_x - 0.6, 0}, speed, std::max(pause_s, 0.05)},
                     {{back_x, 0}, speed},
                     {{back_x - on_m * std::cos(out_turn), on_m * std::sin(out_turn)}, speed}},
                    CornerLimits{.start_stop_accel_mps2 = 1.0});
  s.name = fmt::format("dead_end-{}", seed);
  const double half = width_m / 2;
  s.world.add_wall({kEntryM, -half}, {end_x, -half});
  s.world.add_wall({kEntryM, half}, {end_x, half});
  s.world.add_wall({end_x, -half}, {end_x, half});
  return s;
}

// The constrained worlds' obstacles beside the walk (RandomScenarioOptions), from their own
// generator and after everything else, so the seed's world is unchanged beneath them.
void add_obstacles_beside_walk(Scenario& s, uint32_t seed, double clearance_m) {
  std::mt19937 rng(seed ^ 0x9E3779B9u);
  const std::vector<TimedPose>& walk_samples = s.person.samples();
  // Against a bound of the shape (a box's corners are r sqrt(2) from its centre), so no part of
  // an obstacle comes nearer the walk than the clearance.
  auto clear = [&](core::Point2 c, double bound_m) {
    for (const TimedPose& tp : walk_samples) {
      if (std::hypot(tp.pose.x_m - c.x_m, tp.pose.y_m - c.y_m) < bound_m + clearance_m) {
        return false;
      }
    }
    for (const Pedestrian& p : s.pedestrians) {
      if (std::hypot(p.position.x_m - c.x_m, p.position.y_m - c.y_m) < bound_m + 0.6) return false;
    }
    return std::hypot(s.robot_start.x_m - c.x_m, s.robot_start.y_m - c.y_m) > bound_m + 1.5;
  };
  double walked_m = 0;
  double next_m = uniform(rng, 1.0, 3.0);
  for (size_t k = 1; k < walk_samples.size(); ++k) {
    const core::Pose2& a = walk_samples[k - 1].pose;
    const core::Pose2& b = walk_samples[k].pose;
    walked_m += std::hypot(b.x_m - a.x_m, b.y_m - a.y_m);
    if (walked_m < next_m) continue;
    next_m = walked_m + uniform(rng, 2.0, 4.0);
    const auto sides = rng() % 3;  // left, right, or both: a passage twice the clearance wide
    for (const double side : {1.0, -1.0}) {
      if ((sides == 0 && side < 0) || (sides == 1 && side > 0)) continue;
      const double r = uniform(rng, 0.3, 0.8);
      const bool box = rng() % 2 == 0;
      const double bound_m = box ? r * std::numbers::sqrt2 : r;
      const double off = clearance_m + bound_m + uniform(rng, 0.0, 0.3);
      const core::Point2 c{b.x_m - side * off * std::sin(b.theta_rad),
                           b.y_m + side * off * std::cos(b.theta_rad)};
      if (!clear(c, bound_m)) continue;
      if (box) {
        s.world.add_box({c.x_m - r, c.y_m - r}, {c.x_m + r, c.y_m + r});
      } else {
        s.world.add_circle(c, r);
      }
    }
  }
}

}  // namespace

const std::vector<ScenarioInfo>& builtin_scenarios() {
  static const std::vector<ScenarioInfo> kList{
      {"open", "1: open space, rectangular walk with sharp turns"},
      {"static_obstacle", "2: a static obstacle on one side"},
      {"pedestrian_front_right", "3: a pedestrian approaching from the front-right"},
      {"corridor", "4: a corridor narrowing on both sides"},
      {"doorway", "5: a doorway with a sudden turn behind it"},
      {"crossing", "6: three pedestrians crossing between robot and person"},
      {"random", "7: random static obstacles + 10 pedestrians, 0.7-1.5 m/s (seeded)"},
      {"dead_end", "constrained: a corridor with a closed end, the person turns back (seeded)"},
  };
  return kList;
}

std::optional<Scenario> make_scenario(const std::string& name, uint32_t seed) {
  if (name == "open" || name == "1") return open_space();
  if (name == "static_obstacle" || name == "2") return static_obstacle();
  if (name == "pedestrian_front_right" || name == "3") return pedestrian_front_right();
  if (name == "corridor" || name == "4") return corridor();
  if (name == "doorway" || name == "5") return doorway();
  if (name == "crossing" || name == "6") return crossing();
  if (name == "random" || name == "7") return random_scenario(seed, {});
  if (name == "dead_end") return dead_end(seed);
  return std::nullopt;
}

Scenario random_scenario(uint32_t seed, const RandomScenarioOptions& o) {
  std::mt19937 rng(seed);
  const double speed = uniform(rng, o.speed_min_mps, o.speed_max_mps);
  // The person's walk: legs of 4-8 m with turns up to +-max_turn_rad (100 degrees), inside a
  // 24 m square.
  std::vector<Waypoint> pts{{{0, 0}}};
  double heading = 0;
  double t = kBuiltInStartDelayS;
  core::Point2 p{0, 0};
  // Bounds below 90 degrees would meet the square's edge and turn there by 90 degrees and more
  // (below): such walks steer back toward the middle, more the nearer the edge, within the bound.
  const bool gentle = o.max_turn_rad < std::numbers::pi / 2;
  while (t < o.duration_s - kTailS) {
    for (int attempt = 0; attempt < 20; ++attempt) {
      // The same draw for any bound (the default's walks bit for bit as before it existed).
      double turn = uniform(rng, -o.max_turn_rad, o.max_turn_rad);
      double len = uniform(rng, 4.0, 8.0);
      if (gentle) {
        // Half-length legs (a turn-round fits in the square), and beyond 2 m from the middle
        // a pull toward it, whole from 6 m.
        len /= 2;
        const double pull = std::clamp((std::hypot(p.x_m, p.y_m) - 2.0) / 4.0, 0.0, 1.0);
        const double to_centre = core::wrap_angle(std::atan2(-p.y_m, -p.x_m) - heading);
        turn = std::clamp(turn + pull * to_centre, -o.max_turn_rad, o.max_turn_rad);
      }
      const core::Point2 q{p.x_m + len * std::cos(heading + turn),
                           p.y_m + len * std::sin(heading + turn)};
      if (std::abs(q.x_m) < 12 && std::abs(q.y_m) < 12) {
        heading += turn;
        t += len / speed;
        p = q;
        pts.push_back({q, speed});
        break;
      }
      heading += std::numbers::pi / 2;  // facing a boundary: try around
    }
  }
  Scenario s = base_scenario("random", "random static obstacles and pedestrians", pts,
                             CornerLimits{.turn_rate_radps = o.corner_turn_rate_radps,
                                          .start_stop_accel_mps2 = o.start_stop_accel_mps2});
  s.name = fmt::format("random-{}", seed);
  s.duration_s = std::min(s.duration_s, o.duration_s);
  // Static obstacles: circles and boxes at least 1.6 m from the person's walk and the start.
  auto clear_of_walk = [&](core::Point2 c, double r) {
    for (const TimedPose& tp : s.person.samples()) {
      if (std::hypot(tp.pose.x_m - c.x_m, tp.pose.y_m - c.y_m) < r + 1.6) return false;
    }
    return std::hypot(s.robot_start.x_m - c.x_m, s.robot_start.y_m - c.y_m) > r + 1.5;
  };
  for (int i = 0, tries = 0; i < o.obstacles && tries < 2000; ++tries) {
    const core::Point2 c{uniform(rng, -13, 13), uniform(rng, -13, 13)};
    const double r = uniform(rng, 0.3, 0.8);
    if (!clear_of_walk(c, r)) continue;
    if (rng() % 2 == 0) {
      s.world.add_circle(c, r);
    } else {
      s.world.add_box({c.x_m - r, c.y_m - r}, {c.x_m + r, c.y_m + r});
    }
    ++i;
  }
  // Pedestrians: walking back and forth between two random points of the area.
  std::normal_distribution<double> desired(1.2, 0.2);
  for (int i = 0; i < o.pedestrians; ++i) {
    Pedestrian ped;
    do {
      ped.position = {uniform(rng, -12, 12), uniform(rng, -12, 12)};
    } while (std::hypot(ped.position.x_m, ped.position.y_m) < 3.0 ||
             s.world.distance(ped.position) < 0.6);
    ped.goals = {{uniform(rng, -12, 12), uniform(rng, -12, 12)}, ped.position};
    ped.loop = true;
    ped.desired_speed_mps = std::clamp(desired(rng), 0.6, 1.8);
    ped.radius_m = uniform(rng, 0.2, 0.35);
    s.pedestrians.push_back(ped);
  }
  if (o.beside_walk_clearance_m > 0) add_obstacles_beside_walk(s, seed, o.beside_walk_clearance_m);
  return s;
}

std::optional<Scenario> recorded_scenario(const PedestrianDataset& dataset, int follow_id,
                                          std::string* error) {
  const auto it = dataset.people.find(follow_id);
  if (it == dataset.people.end()) {
    if (error != nullptr) *error = fmt::format("no person with id {} in the file", follow_id);
    return std::nullopt;
  }
  const Trajectory& followed = it->second;
  if (followed.samples().size() < 2) {
    if (error != nullptr) *error = fmt::format("person {} is observed only once", follow_id);
    return std::nullopt;
  }
  // Time shifted so the followed person appears at kBuiltInStartDelayS (the daemon arms meanwhile).
  const double shift = kBuiltInStartDelayS - followed.start_s();
  // Walked smoothly between the 2.5 Hz observations (sim/trajectory.hpp: smooth_track).
  auto shifted = [&](const Trajectory& tr) {
    std::vector<TimedPose> out = smooth_track(tr).samples();
    for (TimedPose& s : out)
      s.t_s += shift;
    return Trajectory(std::move(out));
  };
  Scenario s;
  s.name = fmt::format("recorded-{}", follow_id);
  s.description = fmt::format("recorded pedestrians, following person {}", follow_id);
  s.person = shifted(followed);
  const core::Pose2 p0 = s.person.pose_at(0.0);
  s.robot_start = p0 * core::Pose2{-1.0, 0.0, 0.0};
  for (const auto& [id, tr] : dataset.people) {
    if (id == follow_id) continue;
    const Trajectory moved = shifted(tr);
    // Only those who are around while the followed person walks.
    if (moved.end_s() < kBuiltInStartDelayS || moved.start_s() > s.person.end_s()) continue;
    s.replayed.push_back(moved);
  }
  s.duration_s = s.person.end_s() + kTailS;
  return s;
}

}  // namespace sim
