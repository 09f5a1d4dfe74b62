// The real companiond binary, as systemd runs it: READY, STATUS, STOPPING over a real
// NOTIFY_SOCKET, orderly stop on SIGINT/SIGTERM, refusal of bad configuration.
#include <gtest/gtest.h>

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "support/child_process.hpp"
#include "support/files.hpp"
#include "support/notify_socket.hpp"

using namespace std::chrono_literals;
using test_support::ChildProcess;
using test_support::slurp;

namespace {

std::string write_temp(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + name;
  std::ofstream(path) << text;
  return path;
}

void run_and_stop(int sig) {
  test_support::NotifySocket sock;
  ASSERT_TRUE(sock.ok());
  sock.export_env();
  const std::string cfg = write_temp("companiond-test.yaml", "logging:\n  summary_period_s: 1\n");
  ChildProcess p({COMPANIOND_PATH, "--config", cfg, "--log-sink", "console"});
  unsetenv("NOTIFY_SOCKET");
  ASSERT_TRUE(p.started());

  EXPECT_TRUE(sock.receive_containing("READY=1", 10s).has_value());
  // The first status with measured rates (they need two reports, one second apart).
  const auto status = sock.receive_containing("control 100Hz", 10s);
  ASSERT_TRUE(status.has_value()) << p.output();
  EXPECT_EQ(status->rfind("STATUS=HOLD: tracker silent", 0), 0U) << *status;

  p.signal(sig);
  EXPECT_TRUE(sock.receive_containing("STOPPING=1", 5s).has_value());
  const auto code = p.wait(10s);
  ASSERT_TRUE(code.has_value()) << "companiond did not exit after the signal";
  EXPECT_EQ(*code, 0);
  const std::string out = p.output();
  // It says plainly why it holds, and that it stopped the robot before leaving.
  EXPECT_NE(out.find("HOLD: tracker silent"), std::string::npos) << out;
  EXPECT_NE(out.find("zero velocity commanded; exiting"), std::string::npos) << out;
}

}  // namespace

TEST(Companiond, StartsHoldsAndStopsOnSigint) {
  run_and_stop(SIGINT);
}

TEST(Companiond, StopsOnSigterm) {
  run_and_stop(SIGTERM);
}

TEST(Companiond, RefusesABadConfigNamingFileLineAndKey) {
  const std::string cfg = write_temp("bad.yaml", "mppi:\n  samples: 10\n  lamda: 1\n");
  ChildProcess p({COMPANIOND_PATH, "--config", cfg});
  ASSERT_TRUE(p.started());
  const auto code = p.wait(10s);
  ASSERT_TRUE(code.has_value());
  EXPECT_EQ(*code, 2);
  EXPECT_NE(p.output().find(cfg + ":3: 'mppi.lamda': unknown key"), std::string::npos)
      << p.output();
}

TEST(Companiond, CheckConfigAcceptsTheShippedDefaults) {
  ChildProcess p({COMPANIOND_PATH, "--check-config", COMPANION_DEFAULT_CONFIG});
  ASSERT_TRUE(p.started());
  EXPECT_EQ(p.wait(10s), 0);
  EXPECT_NE(p.output().find(": OK"), std::string::npos);
}

TEST(Companiond, CheckConfigRejectsAMissingFile) {
  ChildProcess p({COMPANIOND_PATH, "--check-config", "/nonexistent.yaml"});
  ASSERT_TRUE(p.started());
  EXPECT_EQ(p.wait(10s), 2);
  EXPECT_NE(p.output().find("/nonexistent.yaml: cannot open"), std::string::npos) << p.output();
}

TEST(Companiond, PrintConfigShowsEffectiveValues) {
  const std::string cfg = write_temp("print.yaml", "mppi:\n  samples: 777\n");
  ChildProcess p({COMPANIOND_PATH, "--config", cfg, "--print-config"});
  ASSERT_TRUE(p.started());
  EXPECT_EQ(p.wait(10s), 0);
  const std::string out = p.output();
  EXPECT_NE(out.find("samples: 777"), std::string::npos) << out;
  EXPECT_NE(out.find("horizon_steps: 100"), std::string::npos) << out;
}

// Real-time permissions withdrawn (no CAP_SYS_NICE / CAP_IPC_LOCK, rtprio and memlock limits 0):
// with realtime.require the daemon refuses to start; without it, it warns once and runs.
namespace {
std::vector<std::string> without_rt(const std::vector<std::string>& args) {
  std::vector<std::string> cmd{"/usr/bin/prlimit",
                               "--rtprio=0",
                               "--memlock=0",
                               "/usr/bin/setpriv",
                               "--bounding-set=-sys_nice,-ipc_lock",
                               "--inh-caps=-sys_nice,-ipc_lock",
                               COMPANIOND_PATH};
  cmd.insert(cmd.end(), args.begin(), args.end());
  return cmd;
}
bool have_rt_tools() {
  return access("/usr/bin/prlimit", X_OK) == 0 && access("/usr/bin/setpriv", X_OK) == 0;
}
}  // namespace

TEST(Companiond, RefusesToStartWithoutRealTimeWhenRequired) {
  if (!have_rt_tools()) GTEST_SKIP() << "prlimit/setpriv (util-linux) not installed";
  const std::string cfg = write_temp("require-rt.yaml", "realtime:\n  require: true\n");
  ChildProcess p(without_rt({"--config", cfg, "--log-sink", "console"}));
  ASSERT_TRUE(p.started());
  const auto code = p.wait(10s);
  ASSERT_TRUE(code.has_value());
  EXPECT_EQ(*code, 1);
  EXPECT_NE(p.output().find("realtime.require is set but"), std::string::npos) << p.output();
}

TEST(Companiond, WarnsOnceAndRunsWithoutRealTimeWhenNotRequired) {
  if (!have_rt_tools()) GTEST_SKIP() << "prlimit/setpriv (util-linux) not installed";
  ChildProcess p(without_rt({"--log-sink", "console", "--duration-s", "0.5"}));
  ASSERT_TRUE(p.started());
  const auto code = p.wait(10s);
  ASSERT_TRUE(code.has_value());
  EXPECT_EQ(*code, 0);
  const std::string out = p.output();
  const auto first = out.find("running WITHOUT real-time guarantees");
  ASSERT_NE(first, std::string::npos) << out;
  EXPECT_EQ(out.find("running WITHOUT real-time guarantees", first + 1), std::string::npos)
      << "one warning, not one per thread";
}

// libgomp's default wait policy spins its workers at the control group's SCHED_FIFO priority
// (firmware/companiond/openmp_wait.hpp): companiond starts itself again with passive, unless the
// environment chose a policy, which it keeps.
namespace {
// The child inherits the environment; the test itself has no other thread to race with.
// NOLINTBEGIN(concurrency-mt-unsafe)
std::string run_briefly_with_omp_wait_policy(const char* value) {
  if (value == nullptr) {
    unsetenv("OMP_WAIT_POLICY");
  } else {
    setenv("OMP_WAIT_POLICY", value, 1);
  }
  ChildProcess p({COMPANIOND_PATH, "--log-sink", "console", "--duration-s", "0.2"});
  unsetenv("OMP_WAIT_POLICY");
  // NOLINTEND(concurrency-mt-unsafe)
  EXPECT_TRUE(p.started());
  EXPECT_EQ(p.wait(10s), 0) << p.output();
  return p.output();
}
}  // namespace

TEST(Companiond, ChoosesThePassiveOpenmpWaitPolicyUnlessTheEnvironmentDoes) {
  const std::string ours = run_briefly_with_omp_wait_policy(nullptr);
  EXPECT_NE(ours.find("wait policy passive (companiond's default"), std::string::npos) << ours;
  EXPECT_EQ(ours.find("companiond starting"), ours.rfind("companiond starting"))
      << "started once after the re-exec: " << ours;
  const std::string theirs = run_briefly_with_omp_wait_policy("active");
  EXPECT_NE(theirs.find("wait policy active (from OMP_WAIT_POLICY"), std::string::npos) << theirs;
}

TEST(Companiond, RefusesAPolicyFileThatDoesNotLoad) {
  // A policy trained for another interactive-space size: the daemon names the mismatch and stops.
  const std::string policy = write_temp("wrong-n.policy", "CMPPOL01");  // header cut short
  const std::string cfg = write_temp("policy.yaml",
                                     "devices:\n  tracker: none\n  lidar: none\n  base: none\n"
                                     "policy:\n  file: \"" +
                                         policy + "\"\n");
  ChildProcess p({COMPANIOND_PATH, "--config", cfg, "--log-sink", "console"});
  ASSERT_TRUE(p.started());
  const auto code = p.wait(10s);
  ASSERT_TRUE(code.has_value());
  EXPECT_EQ(*code, 1);
  EXPECT_NE(p.output().find(policy + ": policy file: truncated header"), std::string::npos)
      << p.output();
}

// ---- the main job: companiond on the simulated world ---------------------------------------

TEST(CompanionSim, RealTimeRunAccompaniesThenSigtermStopsTheBaseAndWritesTheReport) {
  test_support::NotifySocket sock;
  ASSERT_TRUE(sock.ok());
  sock.export_env();
  const std::string dir = ::testing::TempDir() + "companion-sim-rt";
  ChildProcess p({COMPANIOND_PATH, "--config", COMPANION_SIM_CONFIG, "--scenario", "open", "--live",
                  "--log-sink", "console", "--status-file", dir + "-status.json", "--report", dir});
  unsetenv("NOTIFY_SOCKET");
  ASSERT_TRUE(p.started());
  ASSERT_TRUE(sock.receive_containing("READY=1", 10s).has_value()) << p.output();
  // ACTIVE (armed on the simulated devices), then a few more status lines: the person walks from
  // 4 s on and the robot with them.
  for (int i = 0; i < 6; ++i) {
    ASSERT_TRUE(sock.receive_containing("STATUS=ACTIVE", 15s).has_value()) << p.output();
  }
  // The status file is written once a second. Control overruns on a busy shared machine (three
  // within a second) hold the robot for resume_after_ms (as they must), so the file is read after
  // each of the next STATUS=ACTIVE notifications until one snapshot shows ACTIVE (3 s at most).
  std::string status = slurp(dir + "-status.json");
  for (int i = 0; i < 30 && status.find("\"state\":\"ACTIVE\"") == std::string::npos; ++i) {
    ASSERT_TRUE(sock.receive_containing("STATUS=ACTIVE", 15s).has_value()) << p.output();
    status = slurp(dir + "-status.json");
  }
  EXPECT_NE(status.find("\"state\":\"ACTIVE\""), std::string::npos) << status;
  EXPECT_NE(status.find("\"name\":\"control\""), std::string::npos) << status;
  EXPECT_NE(status.find("\"selector\":\"objective\""), std::string::npos) << status;
  {
    // The ACTIVE snapshot above, not the file of a second later.
    const std::string snapshot = dir + "-status-active.json";
    std::ofstream(snapshot) << status;
    ChildProcess show({COMPANIOND_PATH, "--show-status", snapshot});
    ASSERT_TRUE(show.started());
    EXPECT_EQ(show.wait(10s), 0);
    const std::string text = show.output();
    EXPECT_NE(text.find("safety   ACTIVE"), std::string::npos) << text;
    EXPECT_NE(text.find("\ncontrol "), std::string::npos) << "the task table" << text;
  }
  p.signal(SIGTERM);
  const auto code = p.wait(15s);
  ASSERT_TRUE(code.has_value());
  EXPECT_EQ(*code, 0);
  const std::string out = p.output();
  EXPECT_NE(out.find("SIGTERM: stopping the robot"), std::string::npos) << out;
  EXPECT_NE(out.find("zero velocity commanded; exiting"), std::string::npos) << out;
  EXPECT_NE(out.find("base velocity 0.000 0.000 0.000"), std::string::npos) << out;
  EXPECT_NE(out.find("] ACTIVE | objective"), std::string::npos) << "live status line\n" << out;
  EXPECT_NE(slurp(dir + "/report.md").find("| collision | no |"), std::string::npos);
  EXPECT_NE(slurp(dir + "/trajectory.svg").find("<polyline"), std::string::npos);
}

TEST(CompanionSim, SimulatedClockRunsAreIdentical) {
  auto run = [](const std::string& dir) {
    ChildProcess p({COMPANIOND_PATH, "--config", COMPANION_SIM_CONFIG, "--scenario", "crossing",
                    "--duration-s", "9", "--sim-clock", "--report", dir, "--log-sink", "console"});
    EXPECT_TRUE(p.started());
    const auto code = p.wait(120s);
    EXPECT_TRUE(code.has_value());
    EXPECT_EQ(code.value_or(-1), 0) << p.output();
    EXPECT_NE(p.output().find("crossing: SUCCESS"), std::string::npos) << p.output();
    return slurp(dir + "/samples.csv");
  };
  const std::string a = run(::testing::TempDir() + "companion-sim-a");
  const std::string b = run(::testing::TempDir() + "companion-sim-b");
  EXPECT_GT(a.size(), 2000U);
  EXPECT_EQ(a, b) << "same scenario, same seed: the same trajectories";
}

TEST(CompanionSim, RefusesAnUnknownScenarioAndABadPedestrianFile) {
  ChildProcess p({COMPANIOND_PATH, "--config", COMPANION_SIM_CONFIG, "--scenario", "moon"});
  ASSERT_TRUE(p.started());
  EXPECT_EQ(p.wait(10s), 2);
  EXPECT_NE(p.output().find("unknown scenario 'moon'; built-in: open"), std::string::npos)
      << p.output();
  const std::string bad = write_temp("peds.txt", "0 1 2 3\n10 1 x 3\n");
  ChildProcess q({COMPANIOND_PATH, "--config", COMPANION_SIM_CONFIG, "--pedestrians", bad});
  ASSERT_TRUE(q.started());
  EXPECT_EQ(q.wait(10s), 2);
  EXPECT_NE(q.output().find(bad + ":2: column 3 is not a number: 'x'"), std::string::npos)
      << q.output();
}

TEST(CompanionSim, RecordWritesACaptureOtherToolsRead) {
  const std::string dir = ::testing::TempDir() + "companion-capture";
  ChildProcess p({COMPANIOND_PATH, "--config", COMPANION_SIM_CONFIG, "--scenario", "open",
                  "--duration-s", "3", "--record", dir, "--log-sink", "console"});
  ASSERT_TRUE(p.started());
  ASSERT_EQ(p.wait(30s), 0) << p.output();
  const std::string can = slurp(dir + "/base.candump");
  EXPECT_NE(can.find(" can0 421#01"), std::string::npos) << "CAN mode request";
  EXPECT_NE(can.find(" can0 111#"), std::string::npos) << "motion commands";
  EXPECT_NE(can.find(" can0 211#"), std::string::npos) << "base feedback";
  EXPECT_NE(slurp(dir + "/tracker.log").find(" amfi0 "), std::string::npos);
  const std::string pcap = slurp(dir + "/lidar.pcap");
  ASSERT_GT(pcap.size(), 1000U * 1248U) << "~750 packets per second";
  EXPECT_EQ(static_cast<uint8_t>(pcap[0]), 0xD4) << "classic pcap, little-endian magic";
  EXPECT_NE(slurp(dir + "/capture.yaml").find("lidar: lidar.pcap"), std::string::npos);
}
