#pragma once
// Confidence gate of the Amfitrack sensor (ours: no vendor client gates on quality). Pure: frames
// and time are passed in. BAD trips on the first bad frame; GOOD returns only after
// `recover_frames` consecutive good frames, and quality has value hysteresis on top (it must rise
// above `quality_good_min` after falling below `quality_bad_below`).
#include <cstdint>
#include <string_view>

#include "amfitrack/amfiprot_codec.hpp"
#include "hal/clock.hpp"

namespace amfitrack {

enum class Confidence : uint8_t { kGood = 0, kDegraded = 1, kBad = 2 };

enum class GateReason : uint8_t {
  kNone = 0,
  kNoData,
  kStale,  // newest frame older than max_age
  kSourceDisconnected,
  kBFieldBad,        // none / too low / too high / coil defect
  kBFieldUncertain,  // degraded
  kPoseNotTracking,  // no tracking or start-up phases
  kPoseUncertain,    // degraded
  kQualityLow,
  kQuaternionInvalid,  // |q| far from 1, or not finite
  kFrameIdStuck,       // the same frame id again: the device repeats itself
  kRecovering,         // conditions good again, waiting for the streak
};
std::string_view to_string(Confidence c);
std::string_view to_string(GateReason r);

struct GateConfig {
  bool quality_high_is_good = true;  // polarity of the metal-distortion byte (disputed)
  uint8_t quality_bad_below = 100;   // effective quality (0..255) below this: BAD
  uint8_t quality_good_min = 140;    // ... and it must reach this to count as good again
  double quaternion_norm_tolerance = 0.05;
  hal::Nanos max_age = std::chrono::milliseconds(50);  // 6 frames at 120 Hz
  uint32_t recover_frames = 12;  // consecutive good frames before GOOD (100 ms at 120 Hz)
};

struct GateOutput {
  Confidence confidence = Confidence::kBad;
  GateReason reason = GateReason::kNoData;
  uint8_t quality = 0;  // effective quality (polarity applied)
  hal::Nanos age{0};    // of the newest frame
};

class ConfidenceGate {
 public:
  explicit ConfidenceGate(const GateConfig& config) : config_(config) {}

  // A decoded 0x1A frame from the configured sensor, stamped at reception.
  void on_frame(const SensorMeasurement& m, hal::Nanos stamp);
  // The verdict at `now` (staleness needs the time).
  [[nodiscard]] GateOutput evaluate(hal::Nanos now) const;

 private:
  // Verdict of one frame on its own (quality hysteresis state included).
  [[nodiscard]] std::pair<Confidence, GateReason> judge(const SensorMeasurement& m, bool first);

  GateConfig config_;
  bool has_frame_ = false;
  hal::Nanos last_stamp_{0};
  uint32_t last_frame_id_ = 0;
  uint8_t quality_ = 0;
  bool quality_low_ = false;  // value hysteresis state
  Confidence frame_confidence_ = Confidence::kBad;
  GateReason frame_reason_ = GateReason::kNoData;
  uint32_t good_streak_ = 0;
  bool was_bad_ = true;  // starts BAD: GOOD needs a full streak
};

}  // namespace amfitrack
