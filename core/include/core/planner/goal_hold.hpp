#pragma once
// Keeping q^d through a moment without a free point. A pedestrian walking past close to the
// person closes every point of W for a few tenths of a second (their inflated cells cover the
// ellipse); stopping then loses a walking person. For up to `hold` after the last free choice,
// the same point of W (recomputed with the person's current pose, so it moves with them) stays
// the goal; the controller's collision cost still keeps the robot off whatever closed it.
// Pure: time is an argument.
#include "core/planner/interactive_space.hpp"
#include "core/time.hpp"

namespace core {

class GoalHold {
 public:
  explicit GoalHold(Nanos hold) : hold_(hold) {}

  // The selection to use at `now`, from the selector's (`space` already updated).
  Selection update(const Selection& chosen, const InteractiveSpace& space, Nanos now);
  // The last update kept the previous point.
  [[nodiscard]] bool held() const { return held_; }
  // The index of W in use (the policy's previous action), -1 none.
  [[nodiscard]] int index() const { return index_; }

 private:
  Nanos hold_;
  int index_ = -1;
  Nanos chosen_at_{0};  // time of the last free choice
  bool held_ = false;
};

}  // namespace core
