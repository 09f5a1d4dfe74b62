#pragma once
// companion-eval's plan: which trials to run (scenario x variant x selector x seed) and how a
// trial's configuration and world follow from them. reference/evaluation.md, scenarios 1-11.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "firmware/config/daemon_config.hpp"
#include "sim/scenario.hpp"

namespace eval {

// A method of the comparison: how q^d is chosen and which controller tracks it.
struct Method {
  std::string name;        // "objective", "fixed_behind", "fixed_side", "pid", "policy"
  std::string selector;    // policy.selector
  std::string controller;  // control.controller
};
const std::vector<Method>& all_methods();
std::optional<Method> method_by_name(const std::string& name);

// One group of trials with the same world recipe (a table row per method).
struct Case {
  std::string name;      // "open", "random", "crowd-15", "speed-1.2", "size-1.2x0.9", ...
  std::string scenario;  // built-in name, "random", or "recorded"
  int trials = 1;
  sim::RandomScenarioOptions random;        // for "random" and its variants
  double ellipse_a_m = 0, ellipse_b_m = 0;  // > 0: interaction-space size of this case
};

// Case names: the built-ins (open ... crossing, random, dead_end), "crowd-N", "speed-V",
// "size-AxB", "clutter-C" (obstacles beside the walk, C m from it), "turns-D[xR]" (the
// person's turns up to +-D degrees, at most R rad/s), "paper" (scenarios 1-6 +
// random), "crowds" (5/10/15/20), "speeds" (0.75/1.2/1.7), "sizes" (a few a x b), "constrained"
// (clutter 1.2/1.0/0.8 and dead_end). Random and dead_end cases get `random_trials` seeds.
// Unknown names: nullopt and `error`.
std::optional<std::vector<Case>> expand_cases(const std::string& name, int random_trials,
                                              std::string& error);

struct Trial {
  const Case* c = nullptr;
  const Method* method = nullptr;
  uint32_t seed = 1;
  int index = 0;  // within the case
};

// The world of a trial (random cases: a new layout per seed).
sim::Scenario make_world(const Case& c, uint32_t seed);
// The daemon's configuration of a trial.
firmware::DaemonConfig trial_config(const firmware::DaemonConfig& base, const Case& c,
                                    const Method& m);

}  // namespace eval
