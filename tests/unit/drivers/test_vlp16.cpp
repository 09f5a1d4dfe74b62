// The VLP-16 codec and scan assembly on the real captures (tests/data/vlp16) and on packets built
// with the encoder: exact points checked by hand from the bytes, structural invariants, every
// malformed variant rejected for its reason, round trips in all return modes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>

#include "hal/capture/pcap_file.hpp"
#include "vlp16/scan_assembler.hpp"
#include "vlp16/vlp16_codec.hpp"

using namespace std::chrono_literals;

namespace {

std::vector<hal::PcapUdpPacket> read_capture(const std::string& name, uint16_t port = 2368) {
  std::string err;
  auto r = hal::PcapReader::open(std::string(COMPANION_TEST_DATA) + "/vlp16/" + name, err);
  EXPECT_TRUE(r) << err;
  std::vector<hal::PcapUdpPacket> out;
  while (r) {
    auto p = r->next(port);
    if (!p) break;
    out.push_back(std::move(*p));
  }
  return out;
}

TEST(Vlp16, FirstPacketOfTheRealCaptureDecodesToHandComputedPoints) {
  // vlp16_strongest.pcap, packet 0, block 0: azimuth 23424 (234.24 deg), next block 23463
  // (gap 39). Channel 0 bytes "58 09 30": 0x0958 = 2392 x 2 mm = 4.784 m, intensity 48, laser 0
  // (-15 deg, +11.2 mm): x = R cos(w) cos(a) = -2.7005, y = -R cos(w) sin(a) = 3.7498,
  // z = R sin(w) + 0.0112 = -1.2270. Channel 17 (second firing, laser 1): azimuth
  // 23424 + round(39 x 57.6 / 110.592) = 23444, time 55.296 + 2.304 us.
  const auto packets = read_capture("vlp16_strongest.pcap");
  ASSERT_EQ(packets.size(), 84U);
  vlp16::RawDataPacket raw;
  ASSERT_EQ(vlp16::parse_data_packet(packets[0].payload, raw), vlp16::DecodeError::kNone);
  EXPECT_EQ(raw.product, vlp16::Product::kVlp16);
  EXPECT_EQ(raw.mode, vlp16::ReturnMode::kStrongest);
  EXPECT_EQ(raw.blocks[0].azimuth, 23424);
  EXPECT_EQ(vlp16::block_azimuth_gap(raw, 0), 39);
  std::array<vlp16::Point, vlp16::kReturnsPerPacket> pts;
  const size_t n = vlp16::decode_points(raw, {}, pts);
  ASSERT_GT(n, 0U);
  const auto find = [&](uint8_t block, uint8_t channel) -> const vlp16::Point* {
    for (size_t i = 0; i < n; ++i) {
      if (pts[i].block == block && pts[i].channel == channel) return &pts[i];
    }
    return nullptr;
  };
  const auto* p0 = find(0, 0);
  ASSERT_NE(p0, nullptr);
  EXPECT_NEAR(p0->distance_m, 4.784, 1e-5);
  EXPECT_EQ(p0->intensity, 48);
  EXPECT_NEAR(p0->x_m, -2.7005, 2e-4);
  EXPECT_NEAR(p0->y_m, 3.7498, 2e-4);
  EXPECT_NEAR(p0->z_m, -1.2270, 2e-4);
  EXPECT_EQ(p0->ring, 0);
  const auto* p17 = find(0, 17);
  ASSERT_NE(p17, nullptr);
  EXPECT_EQ(p17->azimuth, 23444);
  EXPECT_EQ(p17->laser, 1);
  EXPECT_EQ(p17->ring, 8);  // +1 deg is the 9th lowest elevation
  EXPECT_NEAR(p17->time_offset_us, 57.6, 1e-3);
  EXPECT_NEAR(p17->x_m, -2.6782, 2e-4);
  EXPECT_NEAR(p17->y_m, 3.7464, 2e-4);
  EXPECT_NEAR(p17->z_m, 0.0797, 2e-4);
  const auto* p31 = find(0, 31);
  ASSERT_NE(p31, nullptr);
  EXPECT_EQ(p31->azimuth, 23456);
  EXPECT_NEAR(p31->z_m, 1.2384, 2e-4);
  EXPECT_NEAR(p31->time_offset_us, 89.856, 1e-3);
}

TEST(Vlp16, RealCapturesDecodeWithZeroErrorsAndHoldTheInvariants) {
  for (const char* name : {"vlp16_strongest.pcap", "vlp16_2014_strongest.pcap"}) {
    SCOPED_TRACE(name);
    const auto packets = read_capture(name);
    ASSERT_EQ(packets.size(), 84U);
    uint32_t prev_ts = 0;
    for (size_t i = 0; i < packets.size(); ++i) {
      ASSERT_EQ(packets[i].payload.size(), vlp16::kDataPacketSize);
      vlp16::RawDataPacket raw;
      ASSERT_EQ(vlp16::parse_data_packet(packets[i].payload, raw), vlp16::DecodeError::kNone);
      if (i > 0) {
        const uint32_t dt = raw.timestamp_us - prev_ts;
        EXPECT_TRUE(dt == 1327 || dt == 1328) << "packet " << i << ": " << dt;
      }
      prev_ts = raw.timestamp_us;
      // 384 returns per packet; within a block the channels fire in laser order, and the
      // interpolated azimuth never steps back inside a packet.
      vlp16::DecodeOptions all;
      all.min_range_m = 0;
      std::array<vlp16::Point, vlp16::kReturnsPerPacket> pts;
      const size_t n = vlp16::decode_points(raw, all, pts);
      EXPECT_LE(n, vlp16::kReturnsPerPacket);
      // 384 returns per packet: every channel decodes to a point or has no return (distance 0).
      size_t no_return = 0;
      for (const auto& blk : raw.blocks) {
        no_return += static_cast<size_t>(std::count(blk.distance.begin(), blk.distance.end(), 0));
      }
      EXPECT_EQ(n + no_return, vlp16::kReturnsPerPacket);
      for (size_t k = 1; k < n; ++k) {
        if (pts[k].block == pts[k - 1].block) {
          EXPECT_GT(pts[k].channel, pts[k - 1].channel);
          EXPECT_GE(pts[k].time_offset_us, pts[k - 1].time_offset_us);
        }
        const uint32_t step = (pts[k].azimuth + 36000U - pts[k - 1].azimuth) % 36000U;
        EXPECT_LT(step, 100U) << "azimuth monotone (small forward steps)";
      }
      for (size_t k = 0; k < n; ++k) {
        EXPECT_LE(pts[k].distance_m, 130.0f);
        EXPECT_EQ(pts[k].ring, vlp16::laser_table(raw.product).ring[pts[k].laser]);
      }
    }
  }
}

TEST(Vlp16, RingOrderFollowsElevation) {
  const auto& t = vlp16::laser_table(vlp16::Product::kVlp16);
  std::set<uint8_t> rings(t.ring.begin(), t.ring.end());
  EXPECT_EQ(rings.size(), 16U);
  for (size_t a = 0; a < 16; ++a) {
    for (size_t b = 0; b < 16; ++b) {
      if (t.elevation_rad[a] < t.elevation_rad[b]) {
        EXPECT_LT(t.ring[a], t.ring[b]);
      }
    }
  }
  EXPECT_EQ(t.ring[0], 0);    // -15 deg
  EXPECT_EQ(t.ring[15], 15);  // +15 deg
  EXPECT_NEAR(vlp16::laser_table(vlp16::Product::kPuckHiRes).elevation_rad[15], 10.0 * M_PI / 180.0,
              1e-12);
}

TEST(Vlp16, PositionPacketsOfTheRealCapture) {
  const auto packets = read_capture("vlp16_2014_strongest.pcap", 8308);
  ASSERT_EQ(packets.size(), 16U);
  for (const auto& p : packets) {
    vlp16::PositionPacket pos;
    ASSERT_EQ(vlp16::parse_position_packet(p.payload, pos), vlp16::DecodeError::kNone);
    EXPECT_LT(pos.timestamp_us, vlp16::kHourUs);
  }
  vlp16::PositionPacket pos;
  vlp16::PositionPacket in{123456, vlp16::PpsStatus::kLocked,
                           "$GPRMC,123519,A,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W*6A"};
  const auto bytes = vlp16::encode_position_packet(in);
  ASSERT_EQ(vlp16::parse_position_packet(bytes, pos), vlp16::DecodeError::kNone);
  EXPECT_EQ(pos.timestamp_us, 123456U);
  EXPECT_EQ(pos.pps, vlp16::PpsStatus::kLocked);
  EXPECT_EQ(pos.nmea, in.nmea);
  EXPECT_EQ(vlp16::parse_position_packet(std::span(bytes.data(), 511), pos),
            vlp16::DecodeError::kWrongSize);
}

vlp16::RawDataPacket synthetic(vlp16::ReturnMode mode, uint32_t ts, uint16_t az0, uint32_t seed) {
  std::mt19937 rng(seed);
  vlp16::RawDataPacket p;
  p.mode = mode;
  p.timestamp_us = ts;
  const bool dual = mode == vlp16::ReturnMode::kDual;
  for (size_t b = 0; b < vlp16::kBlocks; ++b) {
    const size_t firing = dual ? b / 2 : b;
    p.blocks[b].azimuth = static_cast<uint16_t>((az0 + 40 * firing) % 36000);
    for (size_t k = 0; k < vlp16::kChannels; ++k) {
      p.blocks[b].distance[k] = static_cast<uint16_t>(rng() % 60000);
      p.blocks[b].intensity[k] = static_cast<uint8_t>(rng());
    }
  }
  return p;
}

TEST(Vlp16, EncoderDecoderRoundTripInEveryReturnMode) {
  for (auto mode :
       {vlp16::ReturnMode::kStrongest, vlp16::ReturnMode::kLast, vlp16::ReturnMode::kDual}) {
    for (auto product :
         {vlp16::Product::kVlp16Early, vlp16::Product::kVlp16, vlp16::Product::kPuckHiRes}) {
      auto in = synthetic(mode, 3'599'999'000U, 35900, 7);
      in.product = product;
      const auto bytes = vlp16::encode_data_packet(in);
      vlp16::RawDataPacket out;
      ASSERT_EQ(vlp16::parse_data_packet(bytes, out), vlp16::DecodeError::kNone);
      EXPECT_EQ(vlp16::encode_data_packet(out), bytes) << "bit for bit";
      EXPECT_EQ(out.mode, mode);
      EXPECT_EQ(out.product, product);
      EXPECT_EQ(out.blocks[11].distance[31], in.blocks[11].distance[31]);
    }
  }
  // And the real packets re-encode to their own bytes.
  for (const auto& p : read_capture("vlp16_2014_strongest.pcap")) {
    vlp16::RawDataPacket raw;
    ASSERT_EQ(vlp16::parse_data_packet(p.payload, raw), vlp16::DecodeError::kNone);
    const auto again = vlp16::encode_data_packet(raw);
    EXPECT_TRUE(std::equal(again.begin(), again.end(), p.payload.begin()));
  }
}

TEST(Vlp16, DualReturnDoesNotDuplicateCoincidingReturnsAndTimesFiringPairs) {
  auto p = synthetic(vlp16::ReturnMode::kDual, 1000, 100, 3);
  // Block 0 (last) and block 1 (strongest) of firing 0: channel 5 saw one return only.
  p.blocks[1].distance[5] = p.blocks[0].distance[5] = 1000;
  p.blocks[1].intensity[5] = p.blocks[0].intensity[5] = 50;
  p.blocks[1].distance[6] = 1200;  // two different returns: both kept
  p.blocks[0].distance[6] = 1500;
  std::array<vlp16::Point, vlp16::kReturnsPerPacket> pts;
  vlp16::DecodeOptions all;
  all.min_range_m = 0;
  all.max_range_m = 200;
  const size_t n = vlp16::decode_points(p, all, pts);
  int ch5 = 0;
  int ch6 = 0;
  for (size_t i = 0; i < n; ++i) {
    if (pts[i].block > 1) continue;
    if (pts[i].channel == 5) ++ch5;
    if (pts[i].channel == 6) ++ch6;
    if (pts[i].block == 0) {
      EXPECT_TRUE(pts[i].last_return);
    }
    if (pts[i].block == 1) {
      EXPECT_FALSE(pts[i].last_return);
    }
  }
  EXPECT_EQ(ch5, 1);
  EXPECT_EQ(ch6, 2);
  // Blocks 2k and 2k+1 are the same firing: the same times; block 2 starts 110.592 us later.
  for (size_t i = 0; i < n; ++i) {
    if (pts[i].block == 3 && pts[i].channel == 0) {
      EXPECT_NEAR(pts[i].time_offset_us, 110.592, 1e-3);
    }
  }
  EXPECT_EQ(vlp16::block_azimuth_gap(p, 1), 40);
  EXPECT_EQ(vlp16::block_azimuth_gap(p, 11), 40) << "the last pair reuses the previous gap";
}

TEST(Vlp16, BeamsWithoutAReturnArePointsAlongTheBeamOnlyWhenAsked) {
  auto p = synthetic(vlp16::ReturnMode::kStrongest, 1000, 9000, 3);
  p.blocks[0].distance[1] = 0;  // laser 1 (+1 degree) of the first firing saw nothing
  std::array<vlp16::Point, vlp16::kReturnsPerPacket> pts;
  vlp16::DecodeOptions skip;
  const size_t n_skip = vlp16::decode_points(p, skip, pts);
  for (size_t i = 0; i < n_skip; ++i) {
    EXPECT_FALSE(pts[i].no_return);
    EXPECT_FALSE(pts[i].block == 0 && pts[i].channel == 1) << "skipped by default";
  }
  vlp16::DecodeOptions clear = skip;
  clear.no_return_range_m = 8.0f;
  const size_t n_clear = vlp16::decode_points(p, clear, pts);
  ASSERT_EQ(n_clear, n_skip + 1);
  int flagged = 0;
  for (size_t i = 0; i < n_clear; ++i) {
    if (!pts[i].no_return) continue;
    ++flagged;
    EXPECT_EQ(pts[i].block, 0);
    EXPECT_EQ(pts[i].channel, 1);
    EXPECT_FLOAT_EQ(pts[i].distance_m, 8.0f);
    // 8 m along the +1 degree beam: 0.14 m up (plus the laser's vertical offset), ~0 m east.
    EXPECT_NEAR(std::hypot(pts[i].x_m, pts[i].y_m), 8.0 * std::cos(M_PI / 180.0), 1e-3);
    EXPECT_NEAR(pts[i].z_m, 8.0 * std::sin(M_PI / 180.0), 0.02);
  }
  EXPECT_EQ(flagged, 1);
}

TEST(Vlp16, MalformedPacketsAreRejectedForTheirReason) {
  const auto good = vlp16::encode_data_packet(synthetic(vlp16::ReturnMode::kStrongest, 5, 0, 1));
  vlp16::RawDataPacket out;
  EXPECT_EQ(vlp16::parse_data_packet(std::span(good.data(), 1205), out),
            vlp16::DecodeError::kWrongSize);
  auto bad = good;
  bad[500] = 0x00;  // block 5 flag
  EXPECT_EQ(vlp16::parse_data_packet(bad, out), vlp16::DecodeError::kBadBlockFlag);
  bad = good;
  bad[1205] = 0x28;  // a VLP-32C
  EXPECT_EQ(vlp16::parse_data_packet(bad, out), vlp16::DecodeError::kUnknownProduct);
  bad = good;
  bad[1204] = 0x3A;
  EXPECT_EQ(vlp16::parse_data_packet(bad, out), vlp16::DecodeError::kUnknownReturnMode);
  bad = good;
  bad[2] = 0xA0;  // azimuth 0x8CA0 = 36000
  bad[3] = 0x8C;
  EXPECT_EQ(vlp16::parse_data_packet(bad, out), vlp16::DecodeError::kBadAzimuth);
  bad = good;
  bad[1203] = 0xFF;  // > one hour of microseconds
  EXPECT_EQ(vlp16::parse_data_packet(bad, out), vlp16::DecodeError::kBadTimestamp);
}

TEST(Vlp16, RandomBytesNeverCrashTheDecoders) {
  std::mt19937 rng(11);
  std::array<vlp16::Point, vlp16::kReturnsPerPacket> pts;
  for (int i = 0; i < 2000; ++i) {
    std::vector<uint8_t> bytes(i % 3 == 0 ? rng() % 1300 : vlp16::kDataPacketSize);
    for (auto& b : bytes)
      b = static_cast<uint8_t>(rng());
    if (i % 2 == 0 && bytes.size() == vlp16::kDataPacketSize) {
      for (size_t b = 0; b < 12; ++b) {  // valid flags so the rest of the parser is exercised
        bytes[b * 100] = 0xFF;
        bytes[b * 100 + 1] = 0xEE;
      }
      bytes[1204] = 0x37 + static_cast<uint8_t>(rng() % 3);
      bytes[1205] = 0x22;
    }
    vlp16::RawDataPacket raw;
    if (vlp16::parse_data_packet(bytes, raw) == vlp16::DecodeError::kNone) {
      const size_t n = vlp16::decode_points(raw, {}, pts);
      ASSERT_LE(n, pts.size());
    }
    vlp16::PositionPacket pos;
    (void)vlp16::parse_position_packet(bytes, pos);
  }
}

// ---- scans -------------------------------------------------------------------------------------

TEST(ScanAssembler, CutsScansAtTheCutAngleWithMonotoneAzimuth) {
  // 84 real packets at 600 rpm = 1.1 revolutions: one complete cut at 0 deg (the capture starts
  // at 234 deg, so the first scan is partial).
  vlp16::ScanConfig cfg;
  vlp16::ScanAssembler a(cfg);
  const auto packets = read_capture("vlp16_strongest.pcap");
  int completed = 0;
  hal::Nanos t = 1s;
  for (const auto& p : packets) {
    vlp16::RawDataPacket raw;
    ASSERT_EQ(vlp16::parse_data_packet(p.payload, raw), vlp16::DecodeError::kNone);
    t += 1327us;
    if (const vlp16::Scan* s = a.add(raw, t)) {
      ++completed;
      EXPECT_TRUE(s->partial);
      ASSERT_FALSE(s->points.empty());
      EXPECT_GE(s->points.front().azimuth, 23424);
      for (size_t i = 1; i < s->points.size(); ++i) {
        EXPECT_GE(s->points[i].azimuth, s->points[i - 1].azimuth);
        EXPECT_GE(s->points[i].time_offset_us, s->points[i - 1].time_offset_us - 1e-3f);
      }
    }
  }
  EXPECT_EQ(completed, 1);
  EXPECT_EQ(a.stats().lost_packets, 0U);
  EXPECT_EQ(a.stats().packets, 84U);
}

TEST(ScanAssembler, FullRevolutionsLossesAndHourRollover) {
  // A synthetic 600 rpm stream (75.4 packets per revolution) starting 0.1 s before the top of
  // the hour, with packets 100..102 lost.
  vlp16::ScanConfig cfg;
  cfg.cut_azimuth = 18000;  // cut behind the robot
  vlp16::ScanAssembler a(cfg);
  const double period = vlp16::ScanAssembler::packet_period_us(vlp16::ReturnMode::kStrongest);
  std::vector<const vlp16::Scan*> scans;
  uint32_t lost_in_scans = 0;
  for (int i = 0; i < 400; ++i) {
    const double t_us = 3'599'900'000.0 + i * period;
    const auto ts = static_cast<uint32_t>(std::fmod(t_us, 3'600'000'000.0));
    // Azimuth at 600 rpm: 36000 units per 100 ms.
    const auto az0 = static_cast<uint16_t>(std::fmod(t_us * 0.36, 36000.0));
    auto raw = synthetic(vlp16::ReturnMode::kStrongest, ts, az0, static_cast<uint32_t>(i));
    for (size_t b = 0; b < 12; ++b) {
      raw.blocks[b].azimuth = static_cast<uint16_t>(
          std::fmod(t_us * 0.36 + vlp16::kBlockUs * 0.36 * static_cast<double>(b), 36000.0));
      raw.blocks[b].distance.fill(5000);
    }
    if (i >= 100 && i <= 102) continue;  // lost on the wire
    const hal::Nanos host(static_cast<int64_t>(i * period * 1000.0) + 5'000'000);
    if (const auto* s = a.add(raw, host)) {
      lost_in_scans += s->lost_packets;
      if (!s->partial) {
        scans.push_back(s);
        EXPECT_NEAR(static_cast<double>(s->points.size()), (75.4 - s->lost_packets) * 384, 400.0)
            << "a revolution, less the lost packets";
        EXPECT_NEAR(std::chrono::duration<double>(s->end - s->start).count(), 0.1, 0.002);
        EXPECT_GE(s->points.front().azimuth, 18000);
      }
    }
  }
  EXPECT_EQ(a.stats().hour_rollovers, 1U);
  EXPECT_EQ(a.stats().lost_packets, 3U);
  EXPECT_EQ(lost_in_scans, 3U);
  EXPECT_GE(scans.size(), 3U);
  // Host times follow the sensor clock: the offset is the host stamp minus the end of packet.
  EXPECT_NEAR(static_cast<double>(a.clock_offset_ns()),
              5e6 - 3'599'900'000.0 * 1000.0 - period * 1000.0, 2000.0);
}

TEST(ScanAssembler, DuplicatesAreDropped) {
  vlp16::ScanAssembler a(vlp16::ScanConfig{});
  const auto raw = synthetic(vlp16::ReturnMode::kStrongest, 1000, 0, 1);
  a.add(raw, 1ms);
  a.add(raw, 2ms);
  EXPECT_EQ(a.stats().duplicates, 1U);
  EXPECT_EQ(a.stats().packets, 1U);
}

}  // namespace
