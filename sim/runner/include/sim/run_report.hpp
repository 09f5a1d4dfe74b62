#pragma once
// A run's report, for a person: metrics (Markdown and JSON), the samples (CSV), and a picture of
// the trajectories (SVG: opens in any browser) with the walls and obstacles, the person, the
// pedestrians, the robot and the chosen companion points.
#include <string>
#include <vector>

#include "sim/run_metrics.hpp"
#include "sim/scenario.hpp"
#include "sim/static_world.hpp"

namespace sim {

struct RunReportInputs {
  const Scenario* scenario = nullptr;
  const RunMetrics* metrics = nullptr;
  const std::vector<RunSample>* samples = nullptr;
  std::vector<double> policy_ms;   // wall time per policy run (may be empty)
  std::vector<double> control_ms;  // wall time per control run (may be empty)
  std::string title;               // e.g. "companiond on 'doorway' (real time)"
  std::string notes;               // free text (e.g. the final status line)
};

// The SVG picture alone.
std::string trajectory_svg(const RunReportInputs& in);
// Markdown summary (metrics table, side distribution, planning times).
std::string report_markdown(const RunReportInputs& in);
std::string metrics_json(const RunReportInputs& in);
std::string samples_csv(const std::vector<RunSample>& samples);
// The world's fixed geometry for plots, one shape a row (world frame, m):
// `segment,x0,y0,x1,y1` (walls, polygon edges) and `circle,x,y,r` (round obstacles).
std::string world_csv(const StaticWorld& world);

// Writes report.md, metrics.json, samples.csv and trajectory.svg into `dir` (created). Returns ""
// or what went wrong.
std::string write_run_report(const std::string& dir, const RunReportInputs& in);

// p-quantile of a sample (copying); NaN when empty.
double quantile(std::vector<double> v, double p);

}  // namespace sim
