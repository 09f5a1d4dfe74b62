#include <gtest/gtest.h>

#include <cmath>

#include "amfitrack/confidence_gate.hpp"

namespace am = amfitrack;
using namespace std::chrono_literals;
using hal::Nanos;

namespace {

am::SensorMeasurement good_frame() {
  am::SensorMeasurement m;
  m.position_m = {1.0, 0.0, 0.0};
  m.quaternion_xyzw = {0, 0, 0, 1};
  m.sensor_status = 0x08;  // source connected, B-field tracking
  m.pose_state_raw = 1;    // tracking
  m.quality_raw = 230;
  return m;
}

// Streams frames at 120 Hz; `edit` changes each frame.
class Stream {
 public:
  explicit Stream(am::GateConfig cfg = {}) : gate(cfg) {}
  template <typename F>
  am::GateOutput frames(int n, F edit) {
    for (int i = 0; i < n; ++i) {
      am::SensorMeasurement m = good_frame();
      m.frame_id = ++id;
      edit(m);
      now += Nanos(8'333'333);
      gate.on_frame(m, now);
    }
    return gate.evaluate(now);
  }
  am::GateOutput good(int n) {
    return frames(n, [](am::SensorMeasurement&) {});
  }
  am::ConfidenceGate gate;
  Nanos now = 10s;
  uint32_t id = 0;
};

}  // namespace

TEST(ConfidenceGate, BadWithoutDataThenGoodAfterTheRecoveryStreak) {
  Stream s;
  EXPECT_EQ(s.gate.evaluate(s.now).reason, am::GateReason::kNoData);
  auto out = s.good(11);
  EXPECT_EQ(out.confidence, am::Confidence::kBad);
  EXPECT_EQ(out.reason, am::GateReason::kRecovering);
  out = s.good(1);
  EXPECT_EQ(out.confidence, am::Confidence::kGood);
  EXPECT_EQ(out.quality, 230);
}

TEST(ConfidenceGate, LowQualityTripsWithinOneFrameAndNeedsHysteresisToRecover) {
  Stream s;
  s.good(20);
  auto out = s.frames(1, [](auto& m) { m.quality_raw = 99; });
  EXPECT_EQ(out.confidence, am::Confidence::kBad) << "one frame is enough";
  EXPECT_EQ(out.reason, am::GateReason::kQualityLow);
  out = s.frames(50, [](auto& m) { m.quality_raw = 120; });  // between the thresholds
  EXPECT_EQ(out.reason, am::GateReason::kQualityLow) << "value hysteresis: 120 < 140";
  out = s.frames(11, [](auto& m) { m.quality_raw = 150; });
  EXPECT_EQ(out.reason, am::GateReason::kRecovering);
  out = s.frames(1, [](auto& m) { m.quality_raw = 150; });
  EXPECT_EQ(out.confidence, am::Confidence::kGood);
  out = s.frames(5, [](auto& m) { m.quality_raw = 120; });
  EXPECT_EQ(out.confidence, am::Confidence::kGood) << "120 is still above the bad threshold";
}

TEST(ConfidenceGate, QualityPolarityIsConfigurable) {
  am::GateConfig cfg;
  cfg.quality_high_is_good = false;
  Stream s(cfg);
  auto out = s.frames(12, [](auto& m) { m.quality_raw = 20; });
  EXPECT_EQ(out.confidence, am::Confidence::kGood);
  EXPECT_EQ(out.quality, 235);
  out = s.frames(1, [](auto& m) { m.quality_raw = 230; });
  EXPECT_EQ(out.reason, am::GateReason::kQualityLow);
}

TEST(ConfidenceGate, TrackingLostIsBadAndUncertainIsDegraded) {
  Stream s;
  s.good(12);
  auto out = s.frames(1, [](auto& m) { m.pose_state_raw = 0; });
  EXPECT_EQ(out.reason, am::GateReason::kPoseNotTracking);
  out = s.frames(1, [](auto& m) { m.pose_state_raw = 5; });  // start-up phase
  EXPECT_EQ(out.reason, am::GateReason::kPoseNotTracking);
  s.good(12);
  out = s.frames(1, [](auto& m) { m.pose_state_raw = 2; });
  EXPECT_EQ(out.confidence, am::Confidence::kDegraded);
  EXPECT_EQ(out.reason, am::GateReason::kPoseUncertain);
  out = s.frames(1, [](auto& m) { m.sensor_status = 0x18; });  // B-field uncertain
  EXPECT_EQ(out.reason, am::GateReason::kBFieldUncertain);
  out = s.frames(1, [](auto& m) { m.sensor_status = 0x38; });  // B-field too low
  EXPECT_EQ(out.reason, am::GateReason::kBFieldBad);
  out = s.frames(1, [](auto& m) { m.sensor_status = 0x00; });
  EXPECT_EQ(out.reason, am::GateReason::kSourceDisconnected);
}

TEST(ConfidenceGate, StaleDataIsBad) {
  Stream s;
  s.good(12);
  EXPECT_EQ(s.gate.evaluate(s.now + 50ms).confidence, am::Confidence::kGood);
  const auto out = s.gate.evaluate(s.now + 51ms);
  EXPECT_EQ(out.confidence, am::Confidence::kBad);
  EXPECT_EQ(out.reason, am::GateReason::kStale);
  EXPECT_EQ(out.age, 51ms);
}

TEST(ConfidenceGate, RepeatedFrameIdsAndBrokenQuaternionsAreBad) {
  Stream s;
  s.good(12);
  am::SensorMeasurement m = good_frame();
  m.frame_id = s.id;  // the same id again
  s.gate.on_frame(m, s.now + 8ms);
  EXPECT_EQ(s.gate.evaluate(s.now + 8ms).reason, am::GateReason::kFrameIdStuck);
  auto out = s.frames(1, [](auto& f) { f.quaternion_xyzw = {0, 0, 0, 0.5}; });
  EXPECT_EQ(out.reason, am::GateReason::kQuaternionInvalid);
  out = s.frames(1, [](auto& f) { f.quaternion_xyzw = {0, 0, NAN, 1}; });
  EXPECT_EQ(out.reason, am::GateReason::kQuaternionInvalid);
  out = s.frames(12, [](auto& f) { f.quaternion_xyzw = {0, 0, 0.7071068, 0.7071068}; });
  EXPECT_EQ(out.confidence, am::Confidence::kGood);
}

TEST(ConfidenceGate, FrameIdWrapIsNotStuck) {
  Stream s;
  s.id = 0xFFFFFE;
  auto out = s.frames(13, [](auto& m) { m.frame_id &= 0xFFFFFF; });
  EXPECT_EQ(out.confidence, am::Confidence::kGood);
}
