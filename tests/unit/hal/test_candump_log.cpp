#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <vector>

#include "hal/can/candump_log.hpp"

using hal::CandumpParse;
using hal::CandumpRecord;
using hal::CanFrame;

namespace {
CandumpRecord parse_ok(const std::string& line) {
  CandumpRecord r;
  std::string err;
  EXPECT_EQ(hal::parse_candump_line(line, r, err), CandumpParse::kRecord) << line << ": " << err;
  return r;
}
std::string parse_error(const std::string& line) {
  CandumpRecord r;
  std::string err;
  EXPECT_EQ(hal::parse_candump_line(line, r, err), CandumpParse::kMalformed) << line;
  return err;
}
}  // namespace

TEST(CandumpLog, ParsesTheReferenceExamples) {
  auto r = parse_ok("(1699999999.123456) can0 111#0096000000000000");
  EXPECT_EQ(r.sec, 1699999999);
  EXPECT_EQ(r.nsec, 123456000);
  EXPECT_EQ(r.iface, "can0");
  EXPECT_EQ(r.frame, CanFrame::standard(0x111, {0x00, 0x96, 0, 0, 0, 0, 0, 0}));

  r = parse_ok("(1699999999.123456789) can0 20000040#0000000000000000");
  EXPECT_EQ(r.nsec, 123456789);
  EXPECT_TRUE(r.frame.error);
  EXPECT_EQ(r.frame.id, 0x40U) << "bus-off error class";

  r = parse_ok("(1.000001) vcan0 1ABCDEF0#0102");
  EXPECT_TRUE(r.frame.extended);
  EXPECT_EQ(r.frame.id, 0x1ABCDEF0U);
  EXPECT_EQ(r.frame.dlc, 2);

  r = parse_ok("(1.000001) can0 421#R");
  EXPECT_TRUE(r.frame.remote);
  EXPECT_EQ(r.frame.dlc, 0);
  r = parse_ok("(1.000001) can0 421#R1");
  EXPECT_EQ(r.frame.dlc, 1);
  r = parse_ok("(1.000001) can0 441#");
  EXPECT_EQ(r.frame.dlc, 0);
  r = parse_ok("(1.000001) can0 111#00.96.00.00 R");  // separators and a direction flag
  EXPECT_EQ(r.frame.dlc, 4);
}

TEST(CandumpLog, IgnoresCommentsAndRejectsMalformedLines) {
  CandumpRecord r;
  std::string err;
  EXPECT_EQ(hal::parse_candump_line("# a comment", r, err), CandumpParse::kIgnored);
  EXPECT_EQ(hal::parse_candump_line("", r, err), CandumpParse::kIgnored);
  EXPECT_NE(parse_error("(1699999999.1234) can0 111#00").find("6 or 9"), std::string::npos);
  EXPECT_NE(parse_error("(1.000001) can0 111#0").find("odd"), std::string::npos);
  EXPECT_NE(parse_error("(1.000001) can0 800#00").find("0x7FF"), std::string::npos);
  EXPECT_NE(parse_error("(1.000001) can0 11#00").find("3 or 8"), std::string::npos);
  EXPECT_NE(parse_error("(1.000001) can0 111#001122334455667788").find("8 data"),
            std::string::npos);
  EXPECT_NE(parse_error("(1.000001) can0 111##100").find("FD"), std::string::npos);
  EXPECT_NE(parse_error("(1.000001) can0 111#GG").find("hex"), std::string::npos);
  EXPECT_NE(parse_error("(1.000001) can0").find("interface"), std::string::npos);
}

TEST(CandumpLog, FormatRoundTrips) {
  for (const std::string line :
       {"(1699999999.123456) can0 111#0096000000000000", "(0.000001) can1 12345678#DEAD",
        "(5.500000) can0 123#R", "(7.000000) can0 20000040#0000000000000000",
        "(8.250000) can0 441#"}) {
    EXPECT_EQ(hal::format_candump_line(parse_ok(line)), line);
  }
  EXPECT_EQ(hal::format_candump_line(parse_ok("(1.123456789) can0 111#01"), true),
            "(1.123456789) can0 111#01");
}

TEST(CandumpLog, ReaderCountsBadLinesAndKeepsGoing) {
  const std::string path = ::testing::TempDir() + "reader.log";
  std::ofstream(path) << "(1.000000) can0 111#01\ngarbage\n(1.5) can0 111#01\n# note\n"
                         "(2.000000) can0 221#0102\n";
  hal::CandumpReader reader(path);
  ASSERT_TRUE(reader.is_open());
  std::vector<uint32_t> ids;
  while (auto r = reader.next())
    ids.push_back(r->frame.id);
  EXPECT_EQ(ids, (std::vector<uint32_t>{0x111, 0x221}));
  EXPECT_EQ(reader.malformed(), 1U) << "the line without 6/9 digits; plain text is ignored";
  EXPECT_NE(reader.last_error().find("line 3"), std::string::npos);
}

// Interoperability with Debian's can-utils: our log goes through log2asc (candump log ->
// Vector ASC) and asc2log (back); frames and relative timing survive.
TEST(CandumpLog, CanUtilsReadWhatWeWrite) {
  if (std::system("command -v log2asc > /dev/null && command -v asc2log > /dev/null") != 0) {
    GTEST_SKIP() << "can-utils not installed";
  }
  const std::string dir = ::testing::TempDir();
  std::vector<CandumpRecord> written;
  {
    hal::CandumpWriter w(dir + "ours.log");
    for (const std::string line :
         {"(1699999999.100000) can0 111#0096000000000000", "(1699999999.120000) can0 221#FF6A",
          "(1699999999.150000) can0 12345678#DEADBEEF", "(1699999999.200000) can0 123#R"}) {
      written.push_back(parse_ok(line));
      w.write(written.back());
    }
  }
  const std::string cmd = "log2asc -I " + dir + "ours.log -O " + dir + "ours.asc can0 && " +
                          "asc2log -I " + dir + "ours.asc -O " + dir + "back.log 2>/dev/null";
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  hal::CandumpReader back(dir + "back.log");
  std::vector<CandumpRecord> read;
  while (auto r = back.next())
    read.push_back(*r);
  EXPECT_EQ(back.malformed(), 0U) << back.last_error();
  ASSERT_EQ(read.size(), written.size());
  auto ns = [](const CandumpRecord& r) { return r.sec * 1'000'000'000LL + r.nsec; };
  for (size_t i = 0; i < read.size(); ++i) {
    EXPECT_EQ(read[i].frame, written[i].frame) << i;
    EXPECT_EQ(ns(read[i]) - ns(read[0]), ns(written[i]) - ns(written[0])) << i;
  }
}
