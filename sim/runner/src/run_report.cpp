#include "sim/run_report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>

namespace sim {

double quantile(std::vector<double> v, double p) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  const auto k = static_cast<size_t>(std::clamp(p, 0.0, 1.0) * static_cast<double>(v.size() - 1));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

namespace {

struct Bounds {
  double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
  void add(double x, double y) {
    x0 = std::min(x0, x);
    y0 = std::min(y0, y);
    x1 = std::max(x1, x);
    y1 = std::max(y1, y);
  }
};

std::string xml_escape(const std::string& s) {
  std::string out;
  for (const char c : s) {
    if (c == '<') {
      out += "&lt;";
    } else if (c == '>') {
      out += "&gt;";
    } else if (c == '&') {
      out += "&amp;";
    } else {
      out += c;
    }
  }
  return out;
}

}  // namespace

std::string trajectory_svg(const RunReportInputs& in) {
  const Scenario& sc = *in.scenario;
  const auto& samples = *in.samples;
  Bounds b;
  for (const RunSample& s : samples) {
    b.add(s.robot.x_m, s.robot.y_m);
    b.add(s.person.x_m, s.person.y_m);
  }
  if (samples.empty()) b.add(0, 0);
  for (const Segment& s : sc.world.segments) {
    // Walls far from the action are clipped by the view box, not allowed to stretch it.
    auto near = [&](const Point2& p) {
      return p.x_m > b.x0 - 4 && p.x_m < b.x1 + 4 && p.y_m > b.y0 - 4 && p.y_m < b.y1 + 4;
    };
    if (near(s.a)) b.add(s.a.x_m, s.a.y_m);
    if (near(s.b)) b.add(s.b.x_m, s.b.y_m);
  }
  const double margin = 1.5;
  b.x0 -= margin;
  b.y0 -= margin;
  b.x1 += margin;
  b.y1 += margin;
  const double scale = 900.0 / std::max(b.x1 - b.x0, b.y1 - b.y0);  // px per m
  const double w = (b.x1 - b.x0) * scale;
  const double h = (b.y1 - b.y0) * scale;
  auto px = [&](double x) { return (x - b.x0) * scale; };
  auto py = [&](double y) { return (b.y1 - y) * scale; };  // y up
  std::string svg = fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{:.0f}\" height=\"{:.0f}\" "
      "viewBox=\"0 0 {:.0f} {:.0f}\" font-family=\"sans-serif\" font-size=\"13\">\n"
      "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n",
      w, h + 70, w, h + 70);
  // 1 m grid.
  for (int i = static_cast<int>(std::ceil(b.x0)); i <= static_cast<int>(std::floor(b.x1)); ++i) {
    const double x = i;
    svg += fmt::format(
        "<line x1=\"{0:.1f}\" y1=\"0\" x2=\"{0:.1f}\" y2=\"{1:.1f}\" stroke=\"#eee\"/>\n", px(x),
        h);
  }
  for (int i = static_cast<int>(std::ceil(b.y0)); i <= static_cast<int>(std::floor(b.y1)); ++i) {
    const double y = i;
    svg += fmt::format(
        "<line x1=\"0\" y1=\"{0:.1f}\" x2=\"{1:.1f}\" y2=\"{0:.1f}\" stroke=\"#eee\"/>\n", py(y),
        w);
  }
  for (const Segment& s : sc.world.segments) {
    svg += fmt::format(
        "<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"#333\" "
        "stroke-width=\"4\"/>\n",
        px(s.a.x_m), py(s.a.y_m), px(s.b.x_m), py(s.b.y_m));
  }
  for (const Circle& c : sc.world.circles) {
    svg += fmt::format("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"{:.1f}\" fill=\"#555\"/>\n",
                       px(c.center.x_m), py(c.center.y_m), c.radius_m * scale);
  }
  // Pedestrians: faint dots every sample.
  std::string peds;
  for (size_t i = 0; i < samples.size(); i += 2) {
    for (const Point2& p : samples[i].pedestrians) {
      peds += fmt::format("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"1.6\"/>", px(p.x_m), py(p.y_m));
    }
  }
  svg += "<g fill=\"#e39b2b\" fill-opacity=\"0.35\">" + peds + "</g>\n";
  // Chosen points q^d (while active): small crosses.
  std::string goals;
  for (size_t i = 0; i < samples.size(); i += 3) {
    const RunSample& s = samples[i];
    if (!s.has_goal || !s.active) continue;
    goals += fmt::format("M{:.1f} {:.1f}h6M{:.1f} {:.1f}v6 ", px(s.goal.x_m) - 3, py(s.goal.y_m),
                         px(s.goal.x_m), py(s.goal.y_m) - 3);
  }
  svg += "<path d=\"" + goals + "\" stroke=\"#2a9d3a\" stroke-width=\"1.2\" fill=\"none\"/>\n";
  auto polyline = [&](auto pick, const char* colour, double width) {
    std::string pts;
    for (const RunSample& s : samples) {
      const core::Pose2 p = pick(s);
      pts += fmt::format("{:.1f},{:.1f} ", px(p.x_m), py(p.y_m));
    }
    return fmt::format(
        "<polyline points=\"{}\" fill=\"none\" stroke=\"{}\" stroke-width=\"{}\" "
        "stroke-linejoin=\"round\"/>\n",
        pts, colour, width);
  };
  svg += polyline([](const RunSample& s) { return s.person; }, "#1f5fbf", 2.5);
  svg += polyline([](const RunSample& s) { return s.robot; }, "#c0392b", 2.5);
  // Every 2 s: the robot's footprint heading tick and a thin link robot-person.
  for (size_t i = 0; i < samples.size(); i += 20) {
    const RunSample& s = samples[i];
    svg += fmt::format(
        "<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"#999\" "
        "stroke-dasharray=\"3 3\"/>\n",
        px(s.robot.x_m), py(s.robot.y_m), px(s.person.x_m), py(s.person.y_m));
    svg += fmt::format(
        "<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"#c0392b\" "
        "stroke-width=\"2\"/>\n",
        px(s.robot.x_m), py(s.robot.y_m), px(s.robot.x_m + 0.4 * std::cos(s.robot.theta_rad)),
        py(s.robot.y_m + 0.4 * std::sin(s.robot.theta_rad)));
    svg += fmt::format(
        "<text x=\"{:.1f}\" y=\"{:.1f}\" fill=\"#777\" font-size=\"10\">{:.0f}s</text>\n",
        px(s.person.x_m) + 4, py(s.person.y_m) - 4, s.t_s);
  }
  // Legend and title.
  const double ly = h + 20;
  svg += fmt::format(
      "<text x=\"10\" y=\"{:.0f}\" font-weight=\"bold\">{}</text>\n"
      "<text x=\"10\" y=\"{:.0f}\"><tspan fill=\"#1f5fbf\">person</tspan>  "
      "<tspan fill=\"#c0392b\">robot</tspan>  <tspan fill=\"#2a9d3a\">chosen points q^d</tspan>  "
      "<tspan fill=\"#e39b2b\">pedestrians</tspan>  <tspan fill=\"#333\">walls/obstacles</tspan>  "
      "grid 1 m, labels: time along the person's walk</text>\n",
      ly, xml_escape(in.title), ly + 22);
  svg += "</svg>\n";
  return svg;
}

std::string report_markdown(const RunReportInputs& in) {
  const RunMetrics& m = *in.metrics;
  std::string md = fmt::format("# {}\n\n{}\n\n", in.title, in.scenario->description);
  md += fmt::format("**Result: {}**{}\n\n", m.success ? "SUCCESS" : "FAILURE",
                    m.success ? "" : " - " + m.failure);
  md += "| metric | value |\n|---|---|\n";
  md += fmt::format("| duration | {:.1f} s (moving allowed {:.1f} s, stops {}) |\n", m.duration_s,
                    m.active_s, m.stops);
  md += fmt::format("| collision | {} |\n", m.collision ? "yes" : "no");
  md += fmt::format("| UT (robot < 0.45 m from the person) | {:.2f} s |\n", m.uncomfortable_s);
  md += fmt::format("| time inside the CBF ellipse (h < 0) | {:.2f} s |\n", m.inside_ellipse_s);
  md += fmt::format("| RMSE e_x / e_y / e_theta | {:.3f} m / {:.3f} m / {:.3f} rad |\n",
                    m.rmse_ex_m, m.rmse_ey_m, m.rmse_etheta_rad);
  md += fmt::format("| person distance min / mean / max (moving) | {:.2f} / {:.2f} / {:.2f} m |\n",
                    m.min_person_distance_m, m.mean_person_distance_m, m.max_person_distance_m);
  md += fmt::format("| longest stretch > 2 m from the person | {:.1f} s |\n", m.longest_far_s);
  auto clearance = [](double v) { return v > 1e6 ? std::string("-") : fmt::format("{:.2f} m", v); };
  md += fmt::format("| min clearance obstacles / people (footprint) | {} / {} |\n",
                    clearance(m.min_static_clearance_m), clearance(m.min_people_clearance_m));
  md += fmt::format("| RMS jerk of the command | {:.1f} m/s^3 |\n", m.rms_jerk);
  if (!in.policy_ms.empty()) {
    md += fmt::format("| policy step p50 / p99 | {:.3f} / {:.3f} ms |\n",
                      quantile(in.policy_ms, 0.5), quantile(in.policy_ms, 0.99));
  }
  if (!in.control_ms.empty()) {
    md += fmt::format("| control step (MPPI-CBF + repair) p50 / p99 | {:.3f} / {:.3f} ms |\n",
                      quantile(in.control_ms, 0.5), quantile(in.control_ms, 0.99));
  }
  md += "\nWhere the robot was around the person while moving (share of the time):\n\n";
  double total = 0;
  for (double t : m.side_time_s)
    total += t;
  md +=
      "| front | front-left | left | behind-left | behind | behind-right | right | front-right |\n";
  md += "|---|---|---|---|---|---|---|---|\n|";
  for (double t : m.side_time_s)
    md += fmt::format(" {:.0f} % |", total > 0 ? 100.0 * t / total : 0.0);
  md += "\n\n![trajectories](trajectory.svg)\n";
  if (!in.notes.empty()) md += "\n```\n" + in.notes + "\n```\n";
  return md;
}

std::string metrics_json(const RunReportInputs& in) {
  const RunMetrics& m = *in.metrics;
  auto q = [](const std::vector<double>& v, double p) {
    return v.empty() ? nlohmann::json(nullptr) : nlohmann::json(quantile(v, p));
  };
  auto clearance = [](double v) { return v > 1e6 ? nlohmann::json(nullptr) : nlohmann::json(v); };
  const nlohmann::json j = {{"scenario", in.scenario->name},
                            {"success", m.success},
                            {"failure", m.failure},
                            {"collision", m.collision},
                            {"duration_s", m.duration_s},
                            {"active_s", m.active_s},
                            {"tracking_s", m.tracking_s},
                            {"uncomfortable_s", m.uncomfortable_s},
                            {"inside_ellipse_s", m.inside_ellipse_s},
                            {"rmse_ex_m", m.rmse_ex_m},
                            {"rmse_ey_m", m.rmse_ey_m},
                            {"rmse_etheta_rad", m.rmse_etheta_rad},
                            {"min_person_distance_m", m.min_person_distance_m},
                            {"mean_person_distance_m", m.mean_person_distance_m},
                            {"max_person_distance_m", m.max_person_distance_m},
                            {"longest_far_s", m.longest_far_s},
                            {"min_static_clearance_m", clearance(m.min_static_clearance_m)},
                            {"min_people_clearance_m", clearance(m.min_people_clearance_m)},
                            {"rms_jerk_mps3", m.rms_jerk},
                            {"stops", m.stops},
                            {"side_time_s", m.side_time_s},
                            {"policy_ms_p50", q(in.policy_ms, 0.5)},
                            {"policy_ms_p99", q(in.policy_ms, 0.99)},
                            {"control_ms_p50", q(in.control_ms, 0.5)},
                            {"control_ms_p99", q(in.control_ms, 0.99)}};
  return j.dump(2) + "\n";
}

std::string samples_csv(const std::vector<RunSample>& samples) {
  std::string out =
      "t_s,robot_x_m,robot_y_m,robot_theta_rad,person_x_m,person_y_m,person_theta_rad,active,"
      "has_goal,goal_x_m,goal_y_m,side,pedestrians,nearest_pedestrian_x_m,nearest_pedestrian_y_m,"
      "nearest_pedestrian_m,cmd_vx_mps,cmd_vy_mps,plan_tracking_cost,plan_collision_cost,"
      "plan_barrier_cost,cmd_wz_radps,person_est_theta_rad,person_est_yaw_rate_radps\n";
  for (const RunSample& s : samples) {
    // The pedestrian nearest the robot (centres): where the close calls were.
    core::Point2 nearest{std::nan(""), std::nan("")};
    double nearest_m = std::nan("");
    for (const core::Point2& p : s.pedestrians) {
      const double d = std::hypot(p.x_m - s.robot.x_m, p.y_m - s.robot.y_m);
      if (!(d >= nearest_m)) {
        nearest = p;
        nearest_m = d;
      }
    }
    out += fmt::format(
        "{:.3f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{},{},{:.4f},{:.4f},{},{},{:.4f},{:.4f},"
        "{:.4f},{:.3f},{:.3f},{:.1f},{:.1f},{:.1f},{:.4f},{:.4f},{:.4f}\n",
        s.t_s, s.robot.x_m, s.robot.y_m, s.robot.theta_rad, s.person.x_m, s.person.y_m,
        s.person.theta_rad, s.active ? 1 : 0, s.has_goal ? 1 : 0, s.goal.x_m, s.goal.y_m, s.side,
        s.pedestrians.size(), nearest.x_m, nearest.y_m, nearest_m, s.cmd_vx_mps, s.cmd_vy_mps,
        s.plan_tracking, s.plan_collision, s.plan_barrier, s.cmd_wz_radps, s.person_est_theta_rad,
        s.person_est_yaw_rate_radps);
  }
  return out;
}

std::string world_csv(const StaticWorld& world) {
  std::string out = "kind,a,b,c,d\n";
  for (const Segment& s : world.segments) {
    out += fmt::format("segment,{:.3f},{:.3f},{:.3f},{:.3f}\n", s.a.x_m, s.a.y_m, s.b.x_m, s.b.y_m);
  }
  for (const Circle& c : world.circles) {
    out += fmt::format("circle,{:.3f},{:.3f},{:.3f},\n", c.center.x_m, c.center.y_m, c.radius_m);
  }
  return out;
}

std::string write_run_report(const std::string& dir, const RunReportInputs& in) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) return fmt::format("cannot create {}: {}", dir, ec.message());
  const std::pair<const char*, std::string> files[] = {
      {"report.md", report_markdown(in)},           {"metrics.json", metrics_json(in)},
      {"samples.csv", samples_csv(*in.samples)},    {"trajectory.svg", trajectory_svg(in)},
      {"world.csv", world_csv(in.scenario->world)},
  };
  for (const auto& [name, text] : files) {
    const std::string path = dir + "/" + name;
    std::ofstream f(path);
    f << text;
    if (!f) return fmt::format("cannot write {}", path);
  }
  return {};
}

}  // namespace sim
