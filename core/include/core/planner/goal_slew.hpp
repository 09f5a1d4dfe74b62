#pragma once
// q^d moved round the ellipse at a bounded rate (ours, off by default). The objective argmin
// jumps: when a pedestrian's band covers the point in use, the next choice may be the other side
// of the person, and the tracking error e = q^d - q^r is that jump until the robot gets there
// (three fifths of the random benchmark's e_x^2: docs/eval/SESSIONS.md, twenty-ninth session). The
// paper's learned selector is trained against such jumps (its action-smoothness reward r^a); its
// q^d "evolves smoothly". Here the point in use steps toward the argmin along W, through free
// points only, at most `points_per_s`; where neither way round is free the argmin is taken at
// once, as without the slew (q^d never waits on a closed point).
// Pure: the time since the last update is an argument.
#include "core/planner/interactive_space.hpp"
#include "core/time.hpp"

namespace core {

class GoalSlew {
 public:
  // points_per_s <= 0: off (the argmin is passed through).
  explicit GoalSlew(double points_per_s) : points_per_s_(points_per_s) {}

  // The selection to use: `chosen` (the argmin over P) approached from `from_index` (the point of
  // W in use, -1: none), `period` after the previous update.
  Selection update(const Selection& chosen, int from_index, const InteractiveSpace& space,
                   Nanos period);

 private:
  double points_per_s_;
  double carry_points_ = 0.0;  // the fraction of a step owed from earlier updates
};

}  // namespace core
