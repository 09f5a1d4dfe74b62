// companion-eval end to end, reduced (CI checks the pipeline, not the numbers): cases and
// methods by name, parallel trials, one CSV row per trial, the tables, the plots; the
// recorded-pedestrian mode; clear refusals.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "support/child_process.hpp"
#include "support/files.hpp"

using namespace std::chrono_literals;
using test_support::ChildProcess;
using test_support::slurp;

namespace {
// Joined here, not inside the argument lists (where a joined literal reads as a missing comma).
constexpr const char* kEvalEnv = "EVAL=" COMPANION_EVAL_PATH;
constexpr const char* kBiwiHotel = COMPANION_PEDESTRIANS "/biwi_hotel.txt";

size_t lines(const std::string& s) {
  size_t n = 0;
  for (char c : s)
    n += c == '\n' ? 1 : 0;
  return n;
}
std::vector<std::string> split(const std::string& line, char sep) {
  std::vector<std::string> out;
  std::stringstream in(line);
  for (std::string field; std::getline(in, field, sep);)
    out.push_back(field);
  return out;
}
// The named column of the CSV row starting with `prefix`, as a number (NaN when either is absent).
double csv_value(const std::string& csv, const std::string& prefix, const std::string& column) {
  std::stringstream in(csv);
  std::string header;
  std::getline(in, header);
  const std::vector<std::string> names = split(header, ',');
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(prefix, 0) != 0) continue;
    const std::vector<std::string> fields = split(line, ',');
    for (size_t i = 0; i < names.size() && i < fields.size(); ++i) {
      if (names[i] == column) return std::stod(fields[i]);
    }
  }
  return std::nan("");
}
}  // namespace

TEST(CompanionEval, RunsCasesAndMethodsByNameAndWritesTablesCsvAndPlots) {
  const std::string out = ::testing::TempDir() + "companion-eval-ci";
  ChildProcess p({COMPANION_EVAL_PATH, "--case", "corridor,crowd-5", "--trials", "2", "--method",
                  "objective,fixed_side,pid", "--duration-s", "8", "--jobs", "2", "--samples",
                  "--costmap-at", "6", "--out", out});
  ASSERT_TRUE(p.started());
  ASSERT_EQ(p.wait(600s), 0) << p.output();
  const std::string csv = slurp(out + "/trials.csv");
  // corridor: 1 trial x 3 methods; crowd-5: 2 trials x 3 methods; plus the header.
  EXPECT_EQ(lines(csv), 1U + 3U + 6U) << csv;
  EXPECT_NE(csv.find("crowd-5,fixed_side,2,crowd-5-2,"), std::string::npos) << csv;
  // The controller's counters per trial: MPPI ran at 100 Hz for most of the 8 s and its
  // structured samples won some steps; the path sample is on, but nothing in the corridor lies
  // on the way to q^d, so its trigger must not plan one; the PID follower has no QP repair and
  // no samples.
  EXPECT_GT(csv_value(csv, "corridor,objective,1,", "control_steps"), 400.0) << csv;
  EXPECT_LE(csv_value(csv, "corridor,objective,1,", "control_steps"), 800.0) << csv;
  EXPECT_GT(csv_value(csv, "corridor,objective,1,", "guided_plans"), 0.0) << csv;
  EXPECT_EQ(csv_value(csv, "corridor,objective,1,", "paths_planned"), 0.0) << csv;
  EXPECT_EQ(csv_value(csv, "corridor,objective,1,", "control_failures"), 0.0) << csv;
  EXPECT_GT(csv_value(csv, "corridor,pid,1,", "control_steps"), 400.0) << csv;
  EXPECT_EQ(csv_value(csv, "corridor,pid,1,", "qp_repairs"), 0.0) << csv;
  EXPECT_EQ(csv_value(csv, "corridor,pid,1,", "guided_plans"), 0.0) << csv;
  const std::string md = slurp(out + "/summary.md");
  EXPECT_NE(md.find("## corridor (1 trial per method)"), std::string::npos) << md;
  EXPECT_NE(md.find("## crowd-5 (2 trials per method)"), std::string::npos) << md;
  EXPECT_NE(md.find("| method | SR % | UT s | e_x m | e_y m | e_θ rad |"), std::string::npos);
  EXPECT_NE(md.find("| pid | "), std::string::npos);
  EXPECT_NE(md.find("trials/min"), std::string::npos);
  EXPECT_FALSE(slurp(out + "/samples/corridor/objective-1.csv").empty());
  // The corridor's walls beside the samples, for the trajectory plot.
  EXPECT_EQ(
      slurp(out + "/samples/corridor/objective-1-world.csv").rfind("kind,a,b,c,d\nsegment,", 0),
      0U);

  ChildProcess plot({"/usr/bin/python3", COMPANION_PLOT_SCRIPT, out});
  ASSERT_TRUE(plot.started());
  ASSERT_EQ(plot.wait(120s), 0) << plot.output();
  for (const char* f : {"sides-corridor.png", "trajectories-crowd-5.png", "errors-corridor.png"}) {
    const std::string png = slurp(out + "/plots/" + f);
    ASSERT_GT(png.size(), 1000U) << f;
    EXPECT_EQ(png.substr(1, 3), "PNG") << f;
  }
  // A costmap snapshot per trial (map_server PGM + YAML, and the obstacle ages), drawn by
  // plot_costmap.py.
  const std::string snap = out + "/costmaps/corridor-objective-1-t6.0";
  EXPECT_NE(slurp(snap + ".yaml").find("image: corridor-objective-1-t6.0.pgm"), std::string::npos);
  EXPECT_EQ(slurp(snap + ".pgm").substr(0, 2), "P5");
  EXPECT_EQ(slurp(snap + "-age.pgm").substr(0, 2), "P5") << "the obstacle ages beside it";
  ChildProcess draw({"/usr/bin/python3", COMPANION_PLOT_COSTMAP_SCRIPT, snap + ".yaml"});
  ASSERT_TRUE(draw.started());
  ASSERT_EQ(draw.wait(120s), 0) << draw.output();
  EXPECT_EQ(slurp(snap + ".png").substr(1, 3), "PNG");
}

TEST(CompanionEval, TheOneCommandBenchmarkWritesEveryTableAndPlot) {
  // sim/eval/run_benchmark.sh, reduced: 1 trial per random case, one method, 2 s trials.
  const std::string out = ::testing::TempDir() + "companion-benchmark-ci";
  ChildProcess p({"/usr/bin/env", kEvalEnv, "TRIALS=1", "VARIANT_TRIALS=1", "WALKERS=2",
                  "METHODS=objective", "DURATION_S=2", "JOBS=2", "bash", COMPANION_BENCHMARK_SCRIPT,
                  out});
  ASSERT_TRUE(p.started());
  ASSERT_EQ(p.wait(900s), 0) << p.output();
  const std::string report = slurp(out + "/REPORT.md");
  for (const char* expected :
       {"trials/min", "\n# paper\n", "## open (1 trial per method)",
        "## random (1 trial per method)", "\n# crowds\n", "## crowd-20 (1 trial per method)",
        "\n# speeds\n", "## speed-1.7 (1 trial per method)", "\n# sizes\n",
        "## size-1.2x0.9 (1 trial per method)", "\n# constrained\n",
        "## clutter-0.8 (1 trial per method)", "## dead_end (1 trial per method)",
        "## crowd density", "| objective | 15 | 1 |", "# recorded-biwi_hotel",
        "# recorded-crowds_zara01", "| failures |"}) {
    EXPECT_NE(report.find(expected), std::string::npos) << expected << "\n" << report;
  }
  // 7 paper cases + 14 variants (the dead end among them) + 2 walkers in each recorded file.
  EXPECT_NE(report.find("25 trials in"), std::string::npos) << report;
  EXPECT_NE(report.find("## recorded (2 trials per method)"), std::string::npos) << report;
  for (const char* f : {"/paper/plots/sides-random.png", "/paper/plots/trajectories-doorway.png",
                        "/crowds/plots/sr-crowds.png", "/speeds/plots/sr-speeds.png",
                        "/sizes/plots/sr-sizes.png", "/constrained/plots/sr-constrained.png",
                        "/recorded-biwi_hotel/plots/trajectories-recorded.png"}) {
    EXPECT_GT(slurp(out + f).size(), 1000U) << f;
  }
}

TEST(CompanionEval, TheBenchmarkCanRunInSittingsIntoOneReport) {
  // A full run is longer than a working session: STEPS runs groups one at a time into the same
  // OUT, and the report gathers every group found there.
  const std::string out = ::testing::TempDir() + "companion-benchmark-sittings";
  for (const char* steps : {"STEPS=sizes", "STEPS=speeds"}) {
    ChildProcess p({"/usr/bin/env", kEvalEnv, "VARIANT_TRIALS=1", "METHODS=objective",
                    "DURATION_S=1", "JOBS=2", steps, "bash", COMPANION_BENCHMARK_SCRIPT, out});
    ASSERT_TRUE(p.started());
    ASSERT_EQ(p.wait(300s), 0) << p.output();
  }
  const std::string report = slurp(out + "/REPORT.md");
  EXPECT_NE(report.find("\n# sizes\n"), std::string::npos) << report;
  EXPECT_NE(report.find("\n# speeds\n"), std::string::npos) << report;
  EXPECT_EQ(report.find("\n# crowds\n"), std::string::npos) << report;
  EXPECT_NE(report.find("6 trials in"), std::string::npos) << report;  // 3 sizes + 3 speeds
  ChildProcess bad(
      {"/usr/bin/env", kEvalEnv, "STEPS=moon", "bash", COMPANION_BENCHMARK_SCRIPT, out});
  ASSERT_TRUE(bad.started());
  EXPECT_EQ(bad.wait(30s), 2);
  EXPECT_NE(bad.output().find("unknown step 'moon'"), std::string::npos) << bad.output();
}

TEST(CompanionEval, FollowsARecordedPersonFromAnyDatasetFile) {
  const std::string out = ::testing::TempDir() + "companion-eval-recorded";
  ChildProcess p({COMPANION_EVAL_PATH, "--pedestrians", kBiwiHotel, "--frame-period", "0.4",
                  "--follow", "203", "--method", "objective", "--duration-s", "8", "--out", out});
  ASSERT_TRUE(p.started());
  ASSERT_EQ(p.wait(300s), 0) << p.output();
  const std::string csv = slurp(out + "/trials.csv");
  EXPECT_EQ(lines(csv), 2U);
  EXPECT_NE(csv.find("recorded,objective,1,recorded-203,"), std::string::npos) << csv;

  // --walkers: the three who walk farthest in biwi_hotel (14.0, 13.9, 13.8 m), one trial each.
  const std::string out3 = ::testing::TempDir() + "companion-eval-recorded-3";
  ChildProcess q({COMPANION_EVAL_PATH, "--pedestrians", kBiwiHotel, "--frame-period", "0.4",
                  "--walkers", "3", "--method", "objective", "--duration-s", "2", "--out", out3});
  ASSERT_TRUE(q.started());
  ASSERT_EQ(q.wait(300s), 0) << q.output();
  const std::string csv3 = slurp(out3 + "/trials.csv");
  EXPECT_EQ(lines(csv3), 4U) << csv3;
  for (const char* row :
       {"recorded,objective,1,recorded-203,", "recorded,objective,2,recorded-304,",
        "recorded,objective,3,recorded-366,"}) {
    EXPECT_NE(csv3.find(row), std::string::npos) << row << "\n" << csv3;
  }
}

namespace {
// companion-eval with `args` exits 2 and names the problem.
void expect_refused(const std::vector<std::string>& args, const std::string& message) {
  std::vector<std::string> argv{COMPANION_EVAL_PATH};
  argv.insert(argv.end(), args.begin(), args.end());
  ChildProcess p(argv);
  ASSERT_TRUE(p.started());
  EXPECT_EQ(p.wait(30s), 2) << p.output();
  EXPECT_NE(p.output().find(message), std::string::npos) << message << "\n" << p.output();
}
}  // namespace

TEST(CompanionEval, RefusesUnknownCasesMethodsAndPersons) {
  expect_refused({"--case", "moon"}, "unknown case 'moon'");
  expect_refused({"--method", "teleport"}, "unknown method 'teleport'");
  expect_refused({"--method", "policy"}, "needs a policy file");
  expect_refused({"--pedestrians", kBiwiHotel, "--follow", "99999"}, "no person with id 99999");
  expect_refused({"--pedestrians", kBiwiHotel, "--follow", "203", "--walkers", "2"},
                 "--follow names one person");
  expect_refused({"--pedestrians", kBiwiHotel, "--walkers", "9999"}, "9999 asked for");
}
