#include "eval_plan.hpp"

#include <fmt/format.h>

#include <cstdlib>
#include <numbers>

namespace eval {

const std::vector<Method>& all_methods() {
  static const std::vector<Method> kMethods{
      {"objective", "objective", "mppi_cbf"},   {"fixed_behind", "fixed_behind", "mppi_cbf"},
      {"fixed_side", "fixed_side", "mppi_cbf"}, {"pid", "objective", "pid_follower"},
      {"policy", "auto", "mppi_cbf"},
  };
  return kMethods;
}

std::optional<Method> method_by_name(const std::string& name) {
  for (const Method& m : all_methods()) {
    if (m.name == name) return m;
  }
  return std::nullopt;
}

namespace {
bool parse_number(const std::string& s, double& out) {
  char* end = nullptr;
  out = std::strtod(s.c_str(), &end);
  return !s.empty() && end == s.c_str() + s.size();
}
}  // namespace

std::optional<std::vector<Case>> expand_cases(const std::string& name, int random_trials,
                                              std::string& error) {
  std::vector<Case> out;
  auto random_case = [&](const std::string& case_name) {
    Case c;
    c.name = case_name;
    c.scenario = "random";
    c.trials = random_trials;
    return c;
  };
  // The dead ends are seeded worlds of their own: `random_trials` of them.
  auto dead_end_case = [&] { return Case{"dead_end", "dead_end", random_trials, {}, 0, 0}; };
  for (const auto& info : sim::builtin_scenarios()) {
    if (name == info.name) {
      if (name == "random") return std::vector<Case>{random_case("random")};
      if (name == "dead_end") return std::vector<Case>{dead_end_case()};
      return std::vector<Case>{Case{info.name, info.name, 1, {}, 0, 0}};
    }
  }
  if (name == "paper") {  // the paper's scenarios 1-7
    for (const auto& info : sim::builtin_scenarios()) {
      if (std::string(info.name) == "random") {
        out.push_back(random_case("random"));
      } else if (std::string(info.name) != "dead_end") {
        out.push_back(Case{info.name, info.name, 1, {}, 0, 0});
      }
    }
    return out;
  }
  if (name == "crowds") {
    for (int n : {5, 10, 15, 20}) {
      Case c = random_case(fmt::format("crowd-{}", n));
      c.random.pedestrians = n;
      out.push_back(c);
    }
    return out;
  }
  if (name == "speeds") {
    for (double v : {0.75, 1.2, 1.7}) {
      Case c = random_case(fmt::format("speed-{}", v));
      c.random.speed_min_mps = c.random.speed_max_mps = v;
      out.push_back(c);
    }
    return out;
  }
  if (name == "sizes") {
    for (const auto& [a, b] : {std::pair{0.8, 0.55}, std::pair{1.0, 0.7}, std::pair{1.2, 0.9}}) {
      Case c = random_case(fmt::format("size-{}x{}", a, b));
      c.ellipse_a_m = a;
      c.ellipse_b_m = b;
      out.push_back(c);
    }
    return out;
  }
  // Constrained worlds: the random world of the same seed with obstacles beside the walk, their
  // surfaces C m from the person's path, and the dead ends: where adaptive selection should pay.
  auto clutter_case = [&](double clearance_m) {
    Case c = random_case(fmt::format("clutter-{}", clearance_m));
    c.random.beside_walk_clearance_m = clearance_m;
    return c;
  };
  if (name == "constrained") {
    for (double clearance_m : {1.2, 1.0, 0.8}) {
      out.push_back(clutter_case(clearance_m));
    }
    out.push_back(dead_end_case());
    return out;
  }
  double v = 0;
  if (name.rfind("clutter-", 0) == 0 && parse_number(name.substr(8), v) && v >= 0.6 && v <= 3) {
    return std::vector<Case>{clutter_case(v)};
  }
  if (name.rfind("crowd-", 0) == 0 && parse_number(name.substr(6), v) && v >= 0 && v <= 100) {
    Case c = random_case(name);
    c.random.pedestrians = static_cast<int>(v);
    return std::vector<Case>{c};
  }
  if (name.rfind("speed-", 0) == 0 && parse_number(name.substr(6), v) && v > 0 && v <= 3) {
    Case c = random_case(name);
    c.random.speed_min_mps = c.random.speed_max_mps = v;
    return std::vector<Case>{c};
  }
  if (name.rfind("size-", 0) == 0) {
    const auto x = name.find('x', 5);
    double a = 0, b = 0;
    if (x != std::string::npos && parse_number(name.substr(5, x - 5), a) &&
        parse_number(name.substr(x + 1), b) && a >= 0.3 && b >= 0.3 && a <= 3 && b <= 3) {
      Case c = random_case(name);
      c.ellipse_a_m = a;
      c.ellipse_b_m = b;
      return std::vector<Case>{c};
    }
  }
  // The random world of the same seed with gentler turns: up to +-D degrees, taken no faster
  // than R rad/s (3 when not given), as the recorded pedestrians turn (thirty-seventh session).
  if (name.rfind("turns-", 0) == 0) {
    const auto x = name.find('x', 6);
    const std::string degrees = name.substr(6, x == std::string::npos ? x : x - 6);
    double d = 0, r = 3.0;
    const bool rate_ok = x == std::string::npos || parse_number(name.substr(x + 1), r);
    if (rate_ok && parse_number(degrees, d) && d >= 0 && d <= 180 && r >= 0.2 && r <= 10) {
      Case c = random_case(name);
      c.random.max_turn_rad = d * std::numbers::pi / 180.0;
      c.random.corner_turn_rate_radps = r;
      return std::vector<Case>{c};
    }
  }
  error = fmt::format(
      "unknown case '{}': a scenario (open, static_obstacle, pedestrian_front_right, corridor, "
      "doorway, crossing, random, dead_end), a group (paper, crowds, speeds, sizes, constrained), "
      "or crowd-N, speed-V, size-AxB, clutter-C, turns-D[xR]",
      name);
  return std::nullopt;
}

sim::Scenario make_world(const Case& c, uint32_t seed) {
  if (c.scenario == "random") {
    sim::Scenario s = sim::random_scenario(seed, c.random);
    s.name = fmt::format("{}-{}", c.name, seed);
    return s;
  }
  return *sim::make_scenario(c.scenario, seed);
}

firmware::DaemonConfig trial_config(const firmware::DaemonConfig& base, const Case& c,
                                    const Method& m) {
  firmware::DaemonConfig cfg = base;
  cfg.devices.tracker = cfg.devices.lidar = cfg.devices.base = "sim";
  cfg.policy.selector = m.selector;
  cfg.control.controller = m.controller;
  cfg.mppi.threads = 1;  // trials run in parallel, one per core
  if (c.ellipse_a_m > 0) {
    cfg.interactive_space.ellipse_a_m = c.ellipse_a_m;
    cfg.interactive_space.ellipse_b_m = c.ellipse_b_m;
  }
  return cfg;
}

}  // namespace eval
