#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>

#include "hal/capture/packet_log.hpp"

namespace {

TEST(PacketLog, ParsesAndFormatsTheDesignsLine) {
  hal::PacketRecord r;
  std::string err;
  ASSERT_EQ(hal::parse_packet_line("(1700000000.123456) amfi0 010000000000ff1600", r, err),
            hal::LogLineParse::kRecord)
      << err;
  EXPECT_EQ(r.sec, 1700000000);
  EXPECT_EQ(r.nsec, 123456000);
  EXPECT_EQ(r.iface, "amfi0");
  EXPECT_EQ(r.bytes, (std::vector<uint8_t>{0x01, 0, 0, 0, 0, 0, 0xFF, 0x16, 0}));
  EXPECT_EQ(hal::format_packet_line(r), "(1700000000.123456) amfi0 010000000000FF1600");
}

TEST(PacketLog, RejectsMalformedLinesWithAReason) {
  hal::PacketRecord r;
  std::string err;
  const std::pair<const char*, const char*> cases[] = {
      {"(1.000001) amfi0 0", "odd number of hex digits"},
      {"(1.000001) amfi0 zz", "bad hex digit"},
      {"(1.000001) amfi0 ", "no packet bytes"},
      {"(1.0001) amfi0 00", "6 or 9 digits"},
      {"(1.000001)amfi0 00", "no space"},
  };
  for (const auto& [line, why] : cases) {
    EXPECT_EQ(hal::parse_packet_line(line, r, err), hal::LogLineParse::kMalformed) << line;
    EXPECT_NE(err.find(why), std::string::npos) << line << " -> " << err;
  }
  EXPECT_EQ(hal::parse_packet_line("# a comment", r, err), hal::LogLineParse::kIgnored);
  const std::string huge = "(1.000001) amfi0 " + std::string(2 * 4097, 'A');
  EXPECT_EQ(hal::parse_packet_line(huge, r, err), hal::LogLineParse::kMalformed);
}

TEST(PacketLog, WriterAndReaderRoundTripAndCountBadLines) {
  char path[] = "/tmp/packet_log_XXXXXX";
  const int fd = mkstemp(path);
  ASSERT_GE(fd, 0);
  close(fd);
  {
    hal::PacketLogWriter w(path);
    ASSERT_TRUE(w.is_open());
    w.write({5, 1000, "amfi0", {1, 2, 3}});
    w.write({6, 2000, "amfi0", {0xAB}});
  }
  { std::ofstream(path, std::ios::app) << "(7.000000) amfi0 XYZ\n"; }
  hal::PacketLogReader r(path);
  auto a = r.next();
  auto b = r.next();
  ASSERT_TRUE(a && b);
  EXPECT_EQ(a->bytes, (std::vector<uint8_t>{1, 2, 3}));
  EXPECT_EQ(b->nsec, 2000);
  EXPECT_FALSE(r.next());
  EXPECT_EQ(r.malformed(), 1U);
  EXPECT_NE(r.last_error().find("line 3"), std::string::npos) << r.last_error();
  std::remove(path);
}

}  // namespace
