#pragma once
// The policy's observation, layout 1: the paper's state s_t = (s^c, s^p, s^o, s^r, s^h, s^a)
// (section IV-A) as one fixed-size float vector, shared by training and the runtime. The layout
// id is stored in every policy file; a change of this layout must change kObservationLayout.
//
// For n interactive-space points (all of W, in index order; a point outside P has zeros and
// flag 0, so the size does not depend on k = |P|):
//   [0, 4n)        s^c: per point i: |P_i - q_h| (m), |P_i| (m), l(P_i) (0..100), G(P_i)
//   [4n, 7n)       s^p: per point i: x, y in base_link (m), in-P flag (0/1)
//   [7n, 7n+256)   s^o: local costmap, 16 x 16 cells of 0.25 m around the robot, in base_link
//                  axes (row-major, row 0 at y = -1.875 m, column 0 at x = -1.875 m), cost / 100
//   +3             s^r: robot velocity vx, vy (m/s), wz (rad/s)
//   +6             s^h: person in base_link: x, y (m), heading (rad), vx, vy (m/s), yaw rate
//   (rad/s) +3             s^a: previous action: its point's x, y in base_link (m), valid flag
//   (0/1)
// Size: 7n + 268 (716 for n = 64). Normalisation (mean, std) lives in the policy file.
#include <cstdint>
#include <span>

#include "core/human/human_ekf.hpp"
#include "core/perception/costmap.hpp"
#include "core/planner/interactive_space.hpp"

namespace core {

inline constexpr uint32_t kObservationLayout = 1;
inline constexpr int kPatchCells = 16;
inline constexpr double kPatchResolutionM = 0.25;

constexpr size_t observation_size(size_t points) {
  return 7 * points + static_cast<size_t>(kPatchCells) * kPatchCells + 3 + 6 + 3;
}

struct ObservationInputs {
  const InteractiveSpace* space = nullptr;  // updated for this step
  const Costmap* costmap = nullptr;
  Pose2 robot_odom;
  double robot_vx_mps = 0, robot_vy_mps = 0, robot_wz_radps = 0;
  HumanState human;          // pose and velocity in base_link
  int previous_action = -1;  // index into W (-1: none)
};

// Writes the observation into `out` (size observation_size(n)); returns false (and writes
// nothing) if the size does not match or an input is missing.
bool build_observation(const ObservationInputs& in, std::span<float> out);

}  // namespace core
