// companion-candiag, the real binary, against the built-in simulated base on a virtual bus.
#include <gtest/gtest.h>

#include <fstream>
#include <regex>
#include <string>
#include <vector>

#include "hal/can/candump_log.hpp"
#include "support/child_process.hpp"

using namespace std::chrono_literals;
using test_support::ChildProcess;

namespace {

using Result = test_support::ToolResult;

Result candiag(std::vector<std::string> args) {
  Result r = test_support::run_tool(CANDIAG_PATH, std::move(args), 30s);
  EXPECT_NE(r.code, -1) << "companion-candiag did not finish";
  return r;
}

}  // namespace

TEST(Candiag, MonitorOnceJsonDescribesTheBase) {
  const auto r = candiag({"--bus", "virtual:cd1", "--sim", "monitor", "--once", "--json"});
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("\"vehicle_state\":\"normal\""), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"control_mode\":\"standby\""), std::string::npos)
      << "monitor only listens: it does not enable CAN mode";
  EXPECT_NE(r.out.find("\"battery_v\":25.2"), std::string::npos) << r.out;
  EXPECT_TRUE(std::regex_search(
      r.out,
      std::regex("\"0x221\":\\{\"count\":[1-9][0-9]*,\"rate_hz\":(3[5-9]|[45][0-9]|6[0-5])")))
      << r.out;
}

TEST(Candiag, CheckPassesOnAHealthyBase) {
  const auto r = candiag({"--bus", "virtual:cd2", "--sim", "check", "--seconds", "1"});
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("check: PASS"), std::string::npos);
  EXPECT_EQ(r.out.find("FAIL"), std::string::npos) << r.out;
}

TEST(Candiag, CheckFailsOnEachFault) {
  for (const std::string fault : {"estop", "rc", "undervoltage", "motor", "silent"}) {
    const auto r = candiag(
        {"--bus", "virtual:cd3", "--sim", "--sim-fault", fault, "check", "--seconds", "0.6"});
    if (fault == "silent") {
      EXPECT_EQ(r.code, 2) << r.out;
      EXPECT_NE(r.out.find("no Scout Mini frames"), std::string::npos) << r.out;
      continue;
    }
    EXPECT_EQ(r.code, 1) << fault << "\n" << r.out;
    EXPECT_NE(r.out.find("check: FAIL"), std::string::npos) << fault;
  }
}

TEST(Candiag, ClearErrorsForNoBaseNoInterfaceAndV1) {
  auto r = candiag({"--bus", "virtual:cd4-empty", "check", "--seconds", "0.3"});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("is the base powered on"), std::string::npos) << r.out;
  r = candiag({"--bus", "socketcan:can7", "check"});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("cannot open the bus: socketcan:can7"), std::string::npos) << r.out;
  r = candiag({"--bus", "virtual:cd5", "--sim", "--sim-v1", "check", "--seconds", "0.3"});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("protocol V1"), std::string::npos) << r.out;
}

TEST(Candiag, JogDrivesThenStops) {
  const auto r =
      candiag({"--bus", "virtual:cd6", "--sim", "jog", "--vx", "0.3", "--duration-s", "1"});
  EXPECT_EQ(r.code, 0) << r.out;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.out, m, std::regex("odometry x \\+([0-9.]+) m"))) << r.out;
  EXPECT_GT(std::stod(m[1]), 0.15) << r.out;
  EXPECT_LT(std::stod(m[1]), 0.45) << r.out;
  EXPECT_NE(r.out.find("velocity now 0.000"), std::string::npos) << "stopped at the end: " << r.out;
}

TEST(Candiag, JogRefusesToDriveAFaultedBase) {
  const auto r =
      candiag({"--bus", "virtual:cd7", "--sim", "--sim-fault", "motor", "jog", "--vx", "0.3"});
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.out.find("jog stopped: base fault"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("odometry x +0.000"), std::string::npos) << r.out;
}

TEST(Candiag, DumpWritesACandumpLogThatParses) {
  const auto r =
      // A frame count, not a time: on a loaded machine 0.3 s held 6 motion frames, not 15.
      candiag({"--bus", "virtual:cd8", "--sim", "dump", "--candump", "--count", "200", "--seconds",
               "60"});
  EXPECT_EQ(r.code, 0);
  int records = 0;
  int motion = 0;
  std::istringstream in(r.out);
  std::string line;
  while (std::getline(in, line)) {
    hal::CandumpRecord rec;
    std::string err;
    if (hal::parse_candump_line(line, rec, err) == hal::CandumpParse::kRecord) {
      ++records;
      if (rec.frame.id == 0x221) ++motion;
      EXPECT_EQ(rec.iface, "can0");
    }
  }
  EXPECT_EQ(records, 200) << r.out;
  EXPECT_GE(motion, 10) << r.out;  // 0x221 is one frame in eight (50 of ~400 a second)
}

TEST(Candiag, ReplayKeepsTheLogTiming) {
  const std::string path = ::testing::TempDir() + "replay.log";
  {
    std::ofstream f(path);
    f << "(1700000000.000000) can0 421#01\n";
    for (int i = 1; i <= 25; ++i) {
      char line[80];
      std::snprintf(line, sizeof(line), "(1700000000.%06d) can0 111#012C000000000000\n", i * 20000);
      f << line;
    }
  }
  const auto r = candiag({"--bus", "virtual:cd9", "--sim", "replay", path});
  EXPECT_EQ(r.code, 0) << r.out;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(
      r.out, m,
      std::regex(
          "replayed 26 frames \\(0 failed, 0 malformed lines\\) in ([0-9.]+) s; log span 0.500 s")))
      << r.out;
  EXPECT_GE(std::stod(m[1]), 0.5);
  EXPECT_LT(std::stod(m[1]), 1.5);
}

TEST(Candiag, SendEnableVersionClearFaultsAndLights) {
  auto r = candiag({"--bus", "virtual:cd10", "--sim", "send", "421#01"});
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("421#01: ok"), std::string::npos);
  r = candiag({"--bus", "virtual:cd10", "--sim", "send", "421#0"});
  EXPECT_EQ(r.code, 3) << r.out;
  r = candiag({"--bus", "virtual:cd11", "--sim", "enable"});
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("control mode: can"), std::string::npos) << r.out;
  r = candiag({"--bus", "virtual:cd12", "--sim", "version"});
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("control sw 2.5"), std::string::npos) << r.out;
  r = candiag({"--bus", "virtual:cd13", "--sim", "--sim-fault", "motor", "clear-faults"});
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("after 0x0000"), std::string::npos) << r.out;
  r = candiag({"--bus", "virtual:cd14", "--sim", "lights", "--mode", "2", "--brightness", "40"});
  EXPECT_EQ(r.code, 0) << r.out;
}
