#include "show_status.hpp"

#include <fmt/format.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>

namespace companiond {

namespace {
using nlohmann::json;

std::string num(const json& v, const char* format = "{:.1f}") {
  if (v.is_number()) return fmt::format(fmt::runtime(format), v.get<double>());
  return "-";
}
std::string yes(const json& v) {
  return v.is_boolean() ? (v.get<bool>() ? "yes" : "no") : "-";
}
std::string str(const json& v) {
  return v.is_string() ? v.get<std::string>() : (v.is_null() ? "-" : v.dump());
}
}  // namespace

int show_status(const std::string& path) {
  std::ifstream f(path);
  if (!f) {
    std::cerr << path << ": cannot open (is companiond running with --status-file " << path
              << "?)\n";
    return 1;
  }
  json j;
  try {
    j = json::parse(f);
  } catch (const json::exception& e) {
    std::cerr << path << ": not a status file: " << e.what() << "\n";
    return 1;
  }
  std::error_code ec;
  const auto written = std::filesystem::last_write_time(path, ec);
  const double age_s =
      ec ? -1.0
         : std::chrono::duration<double>(std::filesystem::file_time_type::clock::now() - written)
               .count();
  std::cout << fmt::format("companiond status ({}; written {:.1f} s ago{})\n", path, age_s,
                           age_s > 3.0 ? " - STALE: is the daemon still running?" : "");
  const json& s = j["safety"];
  std::string reasons;
  for (const auto& r : s.value("active_reasons", json::array()))
    reasons += (reasons.empty() ? "" : ", ") + str(r);
  std::cout << fmt::format("safety   {} ({}, code {})  active: {}\n", str(s["state"]),
                           str(s["reason_text"]), num(s["reason_code"], "{:.0f}"),
                           reasons.empty() ? "-" : reasons);
  const json& g = j["goal"];
  std::cout << fmt::format("goal     {} {} of the person, {} {} m in base_link, {}/{} free ({})\n",
                           str(g["selector"]), str(g["side"]), num(g["x_base_m"], "{:+.2f}"),
                           num(g["y_base_m"], "{:+.2f}"), num(g["free_points"], "{:.0f}"),
                           num(g["points"], "{:.0f}"), str(g["status"]));
  const json& t = j["tracker"];
  std::cout << fmt::format(
      "tracker  link {} {} ({}) quality {} {} Hz, frame age {} ms, person {} m, frames {} drops "
      "{} errors {}\n",
      yes(t["link_up"]), str(t["confidence"]), str(t["gate_reason"]), num(t["quality"], "{:.0f}"),
      num(t["rate_hz"]), num(t["frame_age_ms"], "{:.0f}"), num(t["person_distance_m"], "{:.2f}"),
      num(t["frames"], "{:.0f}"), num(t["dropped_frames"], "{:.0f}"),
      num(t["decode_errors"], "{:.0f}"));
  const json& l = j["lidar"];
  std::cout << fmt::format(
      "lidar    packets {} (age {} ms), costmap age {} ms, scans {}, lost {} drops {} errors {}\n",
      num(l["packets"], "{:.0f}"), num(l["packet_age_ms"], "{:.0f}"),
      num(l["costmap_age_ms"], "{:.0f}"), num(l["scans"], "{:.0f}"),
      num(l["lost_packets"], "{:.0f}"), num(l["kernel_drops"], "{:.0f}"),
      num(l["decode_errors"], "{:.0f}"));
  const json& b = j["base"];
  std::cout << fmt::format(
      "base     CAN mode {} E-stop {} RC {} bus-off {} faults 0x{:04X} write errors {}, feedback "
      "age {} ms, v {} {} {}\n",
      yes(b["can_mode"]), yes(b["estop"]), yes(b["rc_override"]), yes(b["bus_off"]),
      b.value("fault_word", 0), num(b["write_errors"], "{:.0f}"),
      num(b["feedback_age_ms"], "{:.0f}"), num(b["vx_mps"], "{:+.2f}"), num(b["vy_mps"], "{:+.2f}"),
      num(b["wz_radps"], "{:+.2f}"));
  const json& c = j["control"];
  const json bc = c.value("best_cost", json::object());
  std::cout << fmt::format(
      "control  tracking {} runs {} failures {} repairs {} ESS {}, command {} {} {}\n"
      "         best plan cost {} = tracking {} + collision {} + barrier {} + control {}\n",
      yes(c["tracking"]), num(c["runs"], "{:.0f}"), num(c["failures"], "{:.0f}"),
      num(c["repairs"], "{:.0f}"), num(c["effective_samples"], "{:.0f}"),
      num(c["vx_mps"], "{:+.2f}"), num(c["vy_mps"], "{:+.2f}"), num(c["wz_radps"], "{:+.2f}"),
      num(c["min_cost"], "{:.0f}"), num(bc["tracking"], "{:.0f}"), num(bc["collision"], "{:.0f}"),
      num(bc["barrier"], "{:.0f}"), num(bc["control"], "{:.0f}"));
  std::cout << fmt::format("{:<11}{:>8}{:>8}{:>11}{:>9}{:>9}{:>9}{:>8}{:>9}{:>8}{:>12}\n", "task",
                           "rate", "nominal", "jitter p99", "run p50", "run p99", "run max",
                           "budget", "overruns", "skipped", "over budget");
  for (const auto& task : j.value("tasks", json::array())) {
    std::cout << fmt::format(
        "{:<11}{:>8}{:>8}{:>11}{:>9}{:>9}{:>9}{:>8}{:>9}{:>8}{:>12}\n", str(task["name"]),
        num(task["rate_hz"]), num(task["nominal_hz"], "{:.0f}"),
        num(task["jitter_p99_us"], "{:.0f}"), num(task["run_p50_us"], "{:.0f}"),
        num(task["run_p99_us"], "{:.0f}"), num(task["run_max_us"], "{:.0f}"),
        num(task["budget_us"], "{:.0f}"), num(task["overruns"], "{:.0f}"),
        num(task["skipped"], "{:.0f}"), num(task["over_budget"], "{:.0f}"));
  }
  std::cout << "(times in microseconds; the same data: jq . " << path << ")\n";
  return 0;
}

}  // namespace companiond
