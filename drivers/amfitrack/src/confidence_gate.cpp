#include "amfitrack/confidence_gate.hpp"

#include <cmath>

namespace amfitrack {

std::string_view to_string(Confidence c) {
  switch (c) {
    case Confidence::kGood:
      return "GOOD";
    case Confidence::kDegraded:
      return "DEGRADED";
    case Confidence::kBad:
      return "BAD";
  }
  return "?";
}

std::string_view to_string(GateReason r) {
  switch (r) {
    case GateReason::kNone:
      return "ok";
    case GateReason::kNoData:
      return "no data";
    case GateReason::kStale:
      return "stale";
    case GateReason::kSourceDisconnected:
      return "source disconnected";
    case GateReason::kBFieldBad:
      return "B-field not tracking";
    case GateReason::kBFieldUncertain:
      return "B-field uncertain";
    case GateReason::kPoseNotTracking:
      return "pose not tracking";
    case GateReason::kPoseUncertain:
      return "pose uncertain";
    case GateReason::kQualityLow:
      return "quality low";
    case GateReason::kQuaternionInvalid:
      return "quaternion invalid";
    case GateReason::kFrameIdStuck:
      return "frame id stuck";
    case GateReason::kRecovering:
      return "recovering";
  }
  return "?";
}

std::pair<Confidence, GateReason> ConfidenceGate::judge(const SensorMeasurement& m, bool first) {
  quality_ =
      config_.quality_high_is_good ? m.quality_raw : static_cast<uint8_t>(255 - m.quality_raw);
  if (quality_low_ ? quality_ >= config_.quality_good_min : quality_ < config_.quality_bad_below) {
    quality_low_ = !quality_low_;
  }
  if (!first && m.frame_id == last_frame_id_) return {Confidence::kBad, GateReason::kFrameIdStuck};
  if (!m.source_connected()) return {Confidence::kBad, GateReason::kSourceDisconnected};
  const BFieldStatus bf = m.bfield();
  if (bf != BFieldStatus::kTracking && bf != BFieldStatus::kUncertain) {
    return {Confidence::kBad, GateReason::kBFieldBad};
  }
  const auto pose = static_cast<PoseState>(m.pose_state_raw);
  if (pose != PoseState::kTracking && pose != PoseState::kUncertain) {
    return {Confidence::kBad, GateReason::kPoseNotTracking};
  }
  double n2 = 0;
  for (const double q : m.quaternion_xyzw)
    n2 += q * q;
  const double norm = std::sqrt(n2);
  if (!std::isfinite(norm) || std::abs(norm - 1.0) > config_.quaternion_norm_tolerance) {
    return {Confidence::kBad, GateReason::kQuaternionInvalid};
  }
  if (quality_low_) return {Confidence::kBad, GateReason::kQualityLow};
  if (bf == BFieldStatus::kUncertain) return {Confidence::kDegraded, GateReason::kBFieldUncertain};
  if (pose == PoseState::kUncertain) return {Confidence::kDegraded, GateReason::kPoseUncertain};
  return {Confidence::kGood, GateReason::kNone};
}

void ConfidenceGate::on_frame(const SensorMeasurement& m, hal::Nanos stamp) {
  const auto [c, r] = judge(m, !has_frame_);
  has_frame_ = true;
  last_stamp_ = stamp;
  last_frame_id_ = m.frame_id;
  frame_confidence_ = c;
  frame_reason_ = r;
  if (c == Confidence::kBad) {
    was_bad_ = true;
    good_streak_ = 0;
  } else if (++good_streak_ >= config_.recover_frames) {
    was_bad_ = false;
  }
}

GateOutput ConfidenceGate::evaluate(hal::Nanos now) const {
  GateOutput out;
  if (!has_frame_) return out;  // BAD, no data
  out.quality = quality_;
  out.age = now - last_stamp_;
  if (out.age > config_.max_age) {
    out.reason = GateReason::kStale;
    return out;
  }
  if (frame_confidence_ == Confidence::kBad) {
    out.reason = frame_reason_;
    return out;
  }
  if (was_bad_) {
    out.reason = GateReason::kRecovering;
    return out;
  }
  out.confidence = frame_confidence_;
  out.reason = frame_reason_;
  return out;
}

}  // namespace amfitrack
