#include "core/planner/goal_hold.hpp"

namespace core {

Selection GoalHold::update(const Selection& chosen, const InteractiveSpace& space, Nanos now) {
  held_ = false;
  if (chosen.status == GoalStatus::kOk) {
    index_ = chosen.index;
    chosen_at_ = now;
    return chosen;
  }
  const auto points = space.candidates();
  if (chosen.status == GoalStatus::kNoFreePoint && index_ >= 0 &&
      static_cast<size_t>(index_) < points.size() && now - chosen_at_ <= hold_) {
    held_ = true;
    return Selection{GoalStatus::kOk, index_, points[static_cast<size_t>(index_)].base};
  }
  index_ = -1;  // no person, no costmap, or held long enough
  return chosen;
}

}  // namespace core
