#include "core/policy/observation.hpp"

namespace core {

bool build_observation(const ObservationInputs& in, std::span<float> out) {
  if (in.space == nullptr || in.costmap == nullptr) return false;
  const auto cs = in.space->candidates();
  const size_t n = cs.size();
  if (out.size() != observation_size(n)) return false;
  auto f = [](double v) { return static_cast<float>(v); };
  size_t k = 0;
  for (const Candidate& c : cs) {  // s^c
    const bool p = c.free;
    out[k++] = p ? f(c.dist_human_m) : 0.0f;
    out[k++] = p ? f(c.dist_robot_m) : 0.0f;
    out[k++] = p ? f(c.cost) : 0.0f;
    out[k++] = p ? f(c.objective) : 0.0f;
  }
  for (const Candidate& c : cs) {  // s^p
    const bool p = c.free;
    out[k++] = p ? f(c.base.x_m) : 0.0f;
    out[k++] = p ? f(c.base.y_m) : 0.0f;
    out[k++] = p ? 1.0f : 0.0f;
  }
  // s^o: the local patch, sampled at cell centres in base_link, looked up in odom.
  const double half = 0.5 * kPatchCells * kPatchResolutionM;
  for (int row = 0; row < kPatchCells; ++row) {
    for (int col = 0; col < kPatchCells; ++col) {
      const Point2 b{-half + (col + 0.5) * kPatchResolutionM,
                     -half + (row + 0.5) * kPatchResolutionM};
      const Point2 o = in.robot_odom.apply(b);
      out[k++] = f(in.costmap->at(o.x_m, o.y_m) / 100.0);
    }
  }
  out[k++] = f(in.robot_vx_mps);  // s^r
  out[k++] = f(in.robot_vy_mps);
  out[k++] = f(in.robot_wz_radps);
  out[k++] = f(in.human.pose_base.x_m);  // s^h
  out[k++] = f(in.human.pose_base.y_m);
  out[k++] = f(in.human.pose_base.theta_rad);
  out[k++] = f(in.human.velocity_base.x_m);
  out[k++] = f(in.human.velocity_base.y_m);
  out[k++] = f(in.human.yaw_rate_radps);
  const bool prev = in.previous_action >= 0 && static_cast<size_t>(in.previous_action) < n;
  out[k++] = prev ? f(cs[static_cast<size_t>(in.previous_action)].base.x_m) : 0.0f;  // s^a
  out[k++] = prev ? f(cs[static_cast<size_t>(in.previous_action)].base.y_m) : 0.0f;
  out[k++] = prev ? 1.0f : 0.0f;
  return k == out.size();
}

}  // namespace core
