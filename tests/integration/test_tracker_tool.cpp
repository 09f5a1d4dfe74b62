// companion-tracker, the real binary: on the built-in simulated tracker, on a serial port (a
// pseudo-terminal with the simulated device behind it, in real time), and on capture files.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <pty.h>
#include <unistd.h>

#include <fstream>
#include <regex>
#include <string>
#include <vector>

#include "hal/linux_clock.hpp"
#include "sim/sim_amfitrack.hpp"
#include "support/child_process.hpp"

using namespace std::chrono_literals;
using test_support::ChildProcess;

namespace {

using Result = test_support::ToolResult;

Result tracker_tool(std::vector<std::string> args) {
  Result r = test_support::run_tool(TRACKER_TOOL_PATH, std::move(args), 30s);
  EXPECT_NE(r.code, -1) << "companion-tracker did not finish";
  return r;
}

std::string temp_path(const char* name) {
  return ::testing::TempDir() + name;
}

size_t count(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t pos = text.find(what); pos != std::string::npos; pos = text.find(what, pos + 1))
    ++n;
  return n;
}

// The reference's 0x1A test vector, as a capture line.
constexpr const char* kVectorLine =
    "(1700000000.000100) amfi0 3400071a02002e393000b03cffa0860100000000000023ca0a23ca0a0801341200"
    "000000002000000000000064009cff00006e01e60f002d030201ef";

}  // namespace

TEST(TrackerTool, StreamsTheSimulatedSensorAsJson) {
  const auto r = tracker_tool({"--sim", "stream", "--json", "--duration-s", "1.2"});
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_GE(count(r.out, "\"frame_id\":"), 130U) << "120 Hz for 1.2 s";
  EXPECT_NE(r.out.find("\"gate\":\"GOOD\""), std::string::npos) << "good after the streak";
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.out, m, std::regex("\"rate_hz\":([0-9.]+)"))) << r.out;
  EXPECT_NEAR(std::stod(m[1]), 120.0, 6.0);
  EXPECT_NE(r.out.find("\"dropped\":0"), std::string::npos);
}

TEST(TrackerTool, InfoNamesBothDevices) {
  const auto r = tracker_tool({"--sim", "info"});
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("TX   1"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("AMFITRACK SOURCE"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("AMFITRACK SENSOR"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("firmware 0.6.2.0"), std::string::npos) << r.out;
}

TEST(TrackerTool, RecordsACaptureThatDecodesWithoutErrors) {
  const std::string path = temp_path("tracker_record.log");
  const auto rec = tracker_tool({"--sim", "record", path, "--duration-s", "0.5"});
  ASSERT_EQ(rec.code, 0) << rec.out;
  std::ifstream in(path);
  std::string first;
  std::getline(in, first);
  EXPECT_TRUE(std::regex_match(first, std::regex(R"(\(\d+\.\d{6}\) amfi0 [0-9A-F]+)"))) << first;
  const auto dec = tracker_tool({"decode", path, "--strict"});
  EXPECT_EQ(dec.code, 0) << dec.out;
  EXPECT_NE(dec.out.find(" 0 errors"), std::string::npos) << dec.out;
  EXPECT_GE(count(dec.out, " pose "), 50U);
  EXPECT_NE(dec.out.find("name  AMFITRACK SENSOR"), std::string::npos) << "discovery recorded";
}

TEST(TrackerTool, DecodesTheReferenceVectorToItsValues) {
  const std::string path = temp_path("tracker_vector.log");
  std::ofstream(path) << kVectorLine << "\n";
  const auto r = tracker_tool({"decode", path, "--json"});
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("\"frame_id\":66051"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"x_m\":0.12345,\"y_m\":-0.50000,\"z_m\":1.00000"), std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("\"quality\":230"), std::string::npos);
  EXPECT_NE(r.out.find("\"yaw_deg\":90.00"), std::string::npos);
}

TEST(TrackerTool, DecodeReportsBadInputByReason) {
  // A capture with a corrupted payload and a malformed line; and a raw COBS stream with garbage.
  const std::string log = temp_path("tracker_bad.log");
  std::string corrupted = kVectorLine;
  corrupted[40] = corrupted[40] == '0' ? '1' : '0';
  std::ofstream(log) << kVectorLine << "\n" << corrupted << "\n(1.000001) amfi0 XYZ\n";
  const auto r = tracker_tool({"decode", log, "--strict"});
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.out.find("1 packets decoded, 2 errors: 1 malformed lines, 1 bad_payload_crc"),
            std::string::npos)
      << r.out;

  const std::string raw = temp_path("tracker_raw.bin");
  {
    sim::SimAmfitrack dev;
    dev.step(0ms);
    dev.step(20ms);  // frames at 0, 8.3 and 16.7 ms
    auto link = dev.host_link();
    std::vector<uint8_t> bytes = {0x13, 0x37, 0x42};  // garbage before the first delimiter
    bytes.push_back(0);
    while (auto p = link->receive()) {
      auto f = amfitrack::cobs_encode(amfitrack::encode_packet(*p));
      bytes.insert(bytes.end(), f.begin(), f.end());
      bytes.push_back(0);
    }
    std::ofstream(raw, std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()),
               static_cast<std::streamsize>(bytes.size()));
  }
  const auto c = tracker_tool({"decode", raw, "--cobs"});
  EXPECT_EQ(c.code, 0) << c.out;
  EXPECT_EQ(count(c.out, " pose "), 3U) << c.out;
  EXPECT_NE(c.out.find("3 packets decoded, 1 errors"), std::string::npos) << c.out;
}

TEST(TrackerTool, ListSaysWhenNoDeviceIsPlugged) {
  // This machine has no Amfitrack (CI): the tool says so and where to look, exit 1.
  const auto r = tracker_tool({"list"});
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.out.find("no Amfitrack USB devices found"), std::string::npos) << r.out;
}

TEST(TrackerTool, MissingDeviceIsExitTwoWithTheReason) {
  const auto r = tracker_tool({"--device", "serial:/dev/does-not-exist", "stream"});
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("/dev/does-not-exist"), std::string::npos) << r.out;
}

TEST(TrackerTool, StreamsFromASerialPortAndSeesDropsAndQuality) {
  int master = -1;
  int slave = -1;
  char name[256];
  ASSERT_EQ(openpty(&master, &slave, name, nullptr, nullptr), 0);
  ASSERT_EQ(fcntl(master, F_SETFL, fcntl(master, F_GETFL) | O_NONBLOCK), 0);
  ChildProcess p({TRACKER_TOOL_PATH, "--device", std::string("serial:") + name, "stream", "--json",
                  "--duration-s", "1.5"});
  ASSERT_TRUE(p.started());
  // The device runs in real time beside the tool: at 0.5 s three frames are lost, from 0.8 s the
  // quality collapses.
  sim::SimAmfitrack dev;
  hal::LinuxClock clock;
  const hal::Nanos start = clock.now();
  bool dropped = false;
  std::optional<int> code;
  for (hal::Nanos next = start; !(code = p.wait(0ms)); next += 2ms) {
    const hal::Nanos t = clock.now() - start;
    if (t > 500ms && !dropped) {
      dev.drop_frames(3);
      dropped = true;
    }
    if (t > 800ms) dev.set_quality(40);
    dev.step(clock.now());
    ASSERT_TRUE(dev.pump_cobs(master));
    ASSERT_LT(t, 20s) << "the tool did not stop";
    clock.sleep_until(next);
  }
  close(master);
  close(slave);
  const std::string out = p.output();
  EXPECT_EQ(*code, 0) << out;
  EXPECT_NE(out.find("\"dropped\":3"), std::string::npos) << out;
  EXPECT_NE(out.find("\"gate\":\"BAD\",\"gate_reason\":\"quality low\""), std::string::npos);
  EXPECT_NE(out.find("\"gate\":\"GOOD\""), std::string::npos);
  std::smatch m;
  ASSERT_TRUE(std::regex_search(out, m, std::regex("\"rate_hz\":([0-9.]+)"))) << out;
  EXPECT_NEAR(std::stod(m[1]), 120.0, 6.0);
}
