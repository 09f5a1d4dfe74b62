// The daemon's machine-readable status (one JSON object, rebuilt by the report task every second):
// what the README's "Diagnose" section documents. Keys are stable; units are in the names;
// a value that is not known yet is null.
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>

#include "firmware/daemon.hpp"

namespace firmware {

namespace {
using nlohmann::json;

json number(double v) {
  return std::isfinite(v) ? json(v) : json(nullptr);
}

json age_ms(core::Nanos now, core::Nanos stamp) {
  return stamp == core::kNever ? json(nullptr) : json(core::to_ms(now - stamp));
}
}  // namespace

std::string Daemon::build_status_json(core::Nanos now) const {
  json j;
  j["time_s"] = core::to_seconds(now);
  if (const auto s = safety_.read()) {
    json active = json::array();
    for (size_t i = 0; i < core::kReasonCount; ++i) {
      if ((s->value.active_mask >> i & 1U) != 0) active.push_back(core::kReasonTable[i].name);
    }
    j["safety"] = {{"state", core::state_name(s->value.state)},
                   {"reason", core::reason_name(s->value.reason)},
                   {"reason_code", static_cast<int>(s->value.reason)},
                   {"reason_text", core::reason_text(s->value.reason)},
                   {"motion_allowed", s->value.motion_allowed},
                   {"active_reasons", active}};
  }
  if (const auto g = goal_.read()) {
    const CompanionGoal& v = g->value;
    j["goal"] = {{"status", core::to_string(v.status)},
                 {"selector", v.selector},
                 {"side", side_of_person(v.index, v.points)},
                 {"index", v.index},
                 {"x_base_m", number(v.goal_base.x_m)},
                 {"y_base_m", number(v.goal_base.y_m)},
                 {"free_points", v.free_points},
                 {"held", v.held},
                 {"points", v.points},
                 {"age_ms", age_ms(now, g->stamp)}};
  }
  if (const auto t = tracker_health_.read()) {
    const TrackerHealth& h = t->value;
    j["tracker"] = {{"link_up", h.link_up},
                    {"confidence", core::confidence_name(h.confidence)},
                    {"gate_reason", amfitrack::to_string(h.gate_reason)},
                    {"quality", h.quality},
                    {"rate_hz", number(h.rate_hz)},
                    {"frame_age_ms", age_ms(now, h.frame_stamp)},
                    {"person_distance_m", number(h.person_distance_m)},
                    {"frames", h.frames},
                    {"dropped_frames", h.dropped_frames},
                    {"decode_errors", h.decode_errors},
                    {"filter_rejected", h.filter_rejected},
                    {"filter_resets", h.filter_resets}};
  }
  if (const auto l = lidar_health_.read()) {
    const LidarHealth& h = l->value;
    j["lidar"] = {{"packets", h.packets},
                  {"packet_age_ms", age_ms(now, h.packet_stamp)},
                  {"costmap_age_ms", age_ms(now, h.costmap_stamp)},
                  {"scans", h.scans},
                  {"decode_errors", h.decode_errors},
                  {"lost_packets", h.lost_packets},
                  {"kernel_drops", h.kernel_drops},
                  {"obstacle_cells", h.obstacle_cells}};
  }
  if (const auto b = base_health_.read()) {
    const BaseHealth& h = b->value;
    j["base"] = {{"feedback_age_ms", age_ms(now, h.feedback_stamp)},
                 {"can_mode", h.can_mode},
                 {"estop", h.estop},
                 {"rc_override", h.rc_override},
                 {"bus_off", h.bus_off},
                 {"fault_word", h.fault_word},
                 {"write_errors", h.write_errors},
                 {"vx_mps", number(h.vx_mps)},
                 {"vy_mps", number(h.vy_mps)},
                 {"wz_radps", number(h.wz_radps)}};
  }
  if (const auto c = control_status_.read()) {
    const ControlStatus& v = c->value;
    j["control"] = {{"tracking", v.tracking},
                    {"runs", v.runs},
                    {"failures", v.failures},
                    {"repairs", v.repairs},
                    {"closing_limits", v.closing_limits},
                    {"obstacle_limits", v.obstacle_limits},
                    {"guided_plans", v.guided_plans},
                    {"paths_planned", v.paths_planned},
                    {"path_guided_plans", v.path_guided_plans},
                    {"orbits_planned", v.orbits_planned},
                    {"orbit_guided_plans", v.orbit_guided_plans},
                    {"effective_samples", number(v.effective_samples)},
                    {"min_cost", number(v.min_cost)},
                    {"best_cost",
                     {{"tracking", number(v.best_cost.tracking)},
                      {"collision", number(v.best_cost.collision)},
                      {"barrier", number(v.best_cost.barrier)},
                      {"control", number(v.best_cost.control)}}},
                    {"vx_mps", number(v.command.vx_mps)},
                    {"vy_mps", number(v.command.vy_mps)},
                    {"wz_radps", number(v.command.wz_radps)}};
  }
  if (executor_ != nullptr) {
    json tasks = json::array();
    for (size_t i = 0; i < executor_->task_count(); ++i) {
      const auto& st = executor_->stats(i);
      const double rate = i < measured_rate_hz_.size() ? measured_rate_hz_[i]
                                                       : std::numeric_limits<double>::quiet_NaN();
      tasks.push_back({{"name", executor_->spec(i).name},
                       {"rate_hz", number(rate)},
                       {"nominal_hz", executor_->spec(i).rate_hz},
                       {"budget_us", executor_->spec(i).budget_us},
                       {"jitter_p50_us", core::to_us(st.period_jitter().quantile(0.5))},
                       {"jitter_p99_us", core::to_us(st.period_jitter().quantile(0.99))},
                       {"jitter_max_us", core::to_us(st.period_jitter().max())},
                       {"run_p50_us", core::to_us(st.run_time().quantile(0.5))},
                       {"run_p99_us", core::to_us(st.run_time().quantile(0.99))},
                       {"run_max_us", core::to_us(st.run_time().max())},
                       {"runs", st.runs()},
                       {"overruns", st.overruns()},
                       {"skipped", st.skipped()},
                       {"over_budget", st.budget_exceeded()}});
    }
    j["tasks"] = tasks;
  }
  return j.dump() + "\n";
}

}  // namespace firmware
