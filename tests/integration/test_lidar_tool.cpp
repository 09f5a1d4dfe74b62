// companion-lidar, the real binary, on the real VLP-16 captures and on a live UDP stream (the
// capture's packets replayed to it over loopback at the sensor's rate).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "hal/capture/pcap_file.hpp"
#include "hal/linux_clock.hpp"
#include "hal/net/udp_socket.hpp"
#include "support/child_process.hpp"

using namespace std::chrono_literals;
using test_support::ChildProcess;

namespace {

using Result = test_support::ToolResult;

Result lidar_tool(std::vector<std::string> args) {
  Result r = test_support::run_tool(LIDAR_TOOL_PATH, std::move(args), 60s);
  EXPECT_NE(r.code, -1) << "companion-lidar did not finish";
  return r;
}

size_t count_lines_with(const std::string& text, const std::string& what) {
  std::istringstream in(text);
  size_t n = 0;
  for (std::string line; std::getline(in, line);)
    n += line.find(what) != std::string::npos;
  return n;
}

const std::string kCapture = std::string(COMPANION_TEST_DATA) + "/vlp16/vlp16_strongest.pcap";
const std::string k2014 = std::string(COMPANION_TEST_DATA) + "/vlp16/vlp16_2014_strongest.pcap";

}  // namespace

TEST(LidarTool, StatsDescribeTheRealCaptures) {
  auto r = lidar_tool({"stats", kCapture, "--strict"});
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("data packets 84"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("return mode strongest, product VLP-16 / Puck LITE (0x22), 600 rpm"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("lost packets 0"), std::string::npos);
  EXPECT_NE(r.out.find("errors 0"), std::string::npos);
  r = lidar_tool({"stats", k2014});
  EXPECT_NE(r.out.find("(early firmware, 0x21)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("position packets 16"), std::string::npos) << r.out;
}

TEST(LidarTool, DecodeWritesOneRowPerReturnInSensorOrBaseFrame) {
  const std::string csv = ::testing::TempDir() + "returns.csv";
  auto r = lidar_tool({"decode", kCapture, "--sensor-frame", "--out", csv});
  ASSERT_EQ(r.code, 0) << r.out;
  std::ifstream in(csv);
  std::string header;
  std::string first;
  std::getline(in, header);
  std::getline(in, first);
  EXPECT_EQ(header,
            "packet,block,channel,laser,ring,azimuth_deg,distance_m,intensity,x,y,z,time_us");
  // The hand-checked return of the codec test: block 0, channel 0 of the first packet.
  EXPECT_EQ(first, "0,0,0,0,0,234.24,4.784,48,-2.7005,3.7498,-1.2270,596380001.000");
  size_t rows = 1;
  for (std::string line; std::getline(in, line);)
    ++rows;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.out, m, std::regex("returns ([0-9]+)"))) << r.out;
  EXPECT_EQ(rows, std::stoul(m[1]));

  // base_link: the default extrinsic puts the sensor 0.10 m ahead and 0.45 m up.
  r = lidar_tool({"decode", kCapture, "--out", csv});
  std::ifstream in2(csv);
  std::getline(in2, header);
  std::getline(in2, first);
  EXPECT_EQ(first, "0,0,0,0,0,234.24,4.784,48,-2.6005,3.7498,-0.7770,596380001.000");
}

TEST(LidarTool, DecodeWritesAPlyCloudAndPerPacketRows) {
  const std::string ply = ::testing::TempDir() + "cloud.ply";
  auto r = lidar_tool({"decode", kCapture, "--format", "ply", "--out", ply});
  ASSERT_EQ(r.code, 0) << r.out;
  std::ifstream in(ply);
  std::stringstream ss;
  ss << in.rdbuf();
  EXPECT_EQ(ss.str().rfind("ply\nformat ascii 1.0\n", 0), 0U);
  EXPECT_NE(ss.str().find("element vertex 31630\n"), std::string::npos);
  r = lidar_tool({"decode", kCapture, "--per-packet"});
  EXPECT_NE(r.out.find("0,596380001,strongest,0x22,234.24,238.61,375"), std::string::npos);
}

TEST(LidarTool, BadFilesAreClearErrors) {
  auto r = lidar_tool({"stats", "/nonexistent.pcap"});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("/nonexistent.pcap"), std::string::npos) << r.out;
  // A capture with a corrupted packet: counted by reason, --strict fails.
  std::string err;
  auto reader = hal::PcapReader::open(kCapture, err);
  ASSERT_TRUE(reader);
  const std::string bad = ::testing::TempDir() + "bad.pcap";
  {
    auto w = hal::PcapWriter::open(bad, err);
    ASSERT_TRUE(w);
    int i = 0;
    while (auto p = reader->next(2368)) {
      if (i == 3) p->payload[100] = 0x00;  // block 1 flag
      if (i == 5) p->payload.resize(1000);
      w->write(*p);
      ++i;
    }
  }
  r = lidar_tool({"stats", bad, "--strict"});
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.out.find("errors 2 (1 wrong_size, 1 bad_block_flag)"), std::string::npos) << r.out;
}

TEST(LidarTool, ListensToALiveStream) {
  ChildProcess p({LIDAR_TOOL_PATH, "listen", "--bind", "udp:127.0.0.1:0", "--duration-s", "2"});
  ASSERT_TRUE(p.started());
  std::string out;
  std::smatch m;
  uint16_t port = 0;
  while (port == 0) {
    ASSERT_FALSE(p.wait(10ms).has_value()) << p.output();
    out = p.output();
    if (std::regex_search(out, m, std::regex("listening on 127.0.0.1:([0-9]+)"))) {
      port = static_cast<uint16_t>(std::stoul(m[1]));
    }
  }
  // Replay the capture at the sensor's packet rate (1327 us apart).
  std::string err;
  auto reader = hal::PcapReader::open(kCapture, err);
  auto tx = hal::UdpSender::open(err);
  ASSERT_TRUE(reader && tx);
  hal::LinuxClock clock;
  hal::Nanos next = clock.now();
  while (auto pkt = reader->next(2368)) {
    ASSERT_TRUE(tx->send_to({"127.0.0.1", port}, pkt->payload));
    next += 1327us;
    clock.sleep_until(next);
  }
  const auto code = p.wait(10s);
  ASSERT_TRUE(code.has_value());
  out = p.output();
  EXPECT_EQ(*code, 0) << out;
  EXPECT_NE(out.find("total: data packets 84"), std::string::npos) << out;
  EXPECT_NE(out.find("kernel drops 0"), std::string::npos) << out;
}

TEST(LidarTool, CostmapWritesOnePicturePerScanFromTheRealCapture) {
  const std::string dir = ::testing::TempDir() + "costmaps";
  std::filesystem::remove_all(dir);
  const auto r = lidar_tool({"costmap", kCapture, "--out", dir});
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("costmap_0000.pgm: scan 0"), std::string::npos) << r.out;
  std::ifstream in(dir + "/costmap_0000.pgm", std::ios::binary);
  std::string magic, comment_line, size, maxval;
  std::getline(in, magic);
  std::getline(in, comment_line);
  std::getline(in, size);
  std::getline(in, maxval);
  EXPECT_EQ(magic, "P5");
  EXPECT_EQ(size, "240 240");  // 12 m at 5 cm
  std::vector<unsigned char> px(240 * 240);
  in.read(reinterpret_cast<char*>(px.data()), static_cast<std::streamsize>(px.size()));
  ASSERT_EQ(in.gcount(), 240 * 240);
  const auto lethal = std::count(px.begin(), px.end(), 0);
  EXPECT_GT(lethal, 1000) << "the room's walls";
  // The sensor stands at the centre: its own cell is free (self filter, ray clearing).
  EXPECT_EQ(px[120 * 240 + 120], 255);
}

TEST(LidarTool, PcapWeWriteIsReadByTcpdump) {
  // Interop: a capture written by our PcapWriter (the real packets, re-recorded) opens in
  // tcpdump (libpcap's reference reader; Wireshark and VeloView read the same format).
  std::string err;
  auto reader = hal::PcapReader::open(kCapture, err);
  ASSERT_TRUE(reader) << err;
  const std::string out = ::testing::TempDir() + "rerecorded.pcap";
  {
    auto w = hal::PcapWriter::open(out, err);
    ASSERT_TRUE(w) << err;
    while (auto p = reader->next(2368))
      w->write(*p);
  }
  ChildProcess p({"/usr/bin/tcpdump", "-r", out, "-nn", "-tt", "udp", "port", "2368"});
  ASSERT_TRUE(p.started());
  const auto code = p.wait(30s);
  ASSERT_TRUE(code.has_value());
  const std::string text = p.output();
  EXPECT_EQ(*code, 0) << text;
  EXPECT_EQ(count_lines_with(text, "UDP, length 1206"), 84U) << text;
  EXPECT_NE(text.find("1525347606.362040 IP 192.168.1.200.2368 > 255.255.255.255.2368"),
            std::string::npos)
      << "capture time and addresses kept: " << text.substr(0, 300);
}
