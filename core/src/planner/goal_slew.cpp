#include "core/planner/goal_slew.hpp"

#include <algorithm>
#include <cmath>

namespace core {
namespace {

int wrap(int i, int n) {
  return ((i % n) + n) % n;
}  // an index round W

// All points strictly after `from` up to `to` going `dir` (+1 / -1) round W are free.
bool free_way(std::span<const Candidate> points, int from, int steps, int dir) {
  const int n = static_cast<int>(points.size());
  for (int k = 1; k <= steps; ++k) {
    const int i = wrap(from + dir * k, n);
    if (!points[static_cast<size_t>(i)].free) return false;
  }
  return true;
}

}  // namespace

Selection GoalSlew::update(const Selection& chosen, int from_index, const InteractiveSpace& space,
                           Nanos period) {
  const auto points = space.candidates();
  const int n = static_cast<int>(points.size());
  if (points_per_s_ <= 0.0 || chosen.status != GoalStatus::kOk || from_index < 0 ||
      from_index >= n || chosen.index < 0 || chosen.index >= n || chosen.index == from_index) {
    carry_points_ = 0.0;
    return chosen;
  }
  const int ahead = wrap(chosen.index - from_index, n);  // steps going +1
  const int behind = n - ahead;                          // steps going -1
  const bool free_ahead = free_way(points, from_index, ahead, +1);
  const bool free_behind = free_way(points, from_index, behind, -1);
  int dir = 0;
  int distance = 0;
  if (free_ahead && (!free_behind || ahead <= behind)) {
    dir = +1;
    distance = ahead;
  } else if (free_behind) {
    dir = -1;
    distance = behind;
  } else {
    carry_points_ = 0.0;
    return chosen;  // no free way round: the argmin at once
  }
  const double budget = carry_points_ + points_per_s_ * to_seconds(period);
  // Off a closed point at once (at least one step), otherwise as the rate allows.
  const int min_steps = points[static_cast<size_t>(from_index)].free ? 0 : 1;
  // (1e-9: 30 points a second over a period of 33 333 333 ns is a whole step, not 0.99999999.)
  const int steps = std::clamp(static_cast<int>(std::floor(budget + 1e-9)), min_steps, distance);
  carry_points_ = steps == distance ? 0.0 : std::max(0.0, budget - steps);
  const int index = wrap(from_index + dir * steps, n);  // steps = 0: the point in use
  return Selection{GoalStatus::kOk, index, points[static_cast<size_t>(index)].base};
}

}  // namespace core
