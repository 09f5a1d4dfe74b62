// libFuzzer: recorded pedestrian files ("frame id x y" lines from anywhere) must load or give a
// clear error, never crash or hang; a loaded dataset must be usable (finite poses, and finite,
// bounded walks as the recorded scenario makes them).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "sim/pedestrian_dataset.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const sim::DatasetLoad r = sim::parse_pedestrian_dataset(text, 0.4, "fuzz");
  if (!r.ok) {
    if (r.error.empty()) std::abort();  // an error must say what
    return 0;
  }
  for (const auto& [id, tr] : r.data.people) {
    const double mid = 0.5 * (tr.start_s() + tr.end_s());
    const auto p = tr.pose_at(mid);
    const auto v = tr.velocity_at(mid);
    // Finite inputs give finite poses (velocities may overflow for absurd coordinates).
    if (!std::isfinite(p.theta_rad)) std::abort();
    (void)v;
    (void)sim::path_length(tr);
    // As the recorded scenario walks them: finite everywhere (coordinates and frame periods are
    // bounded at load), and a bounded number of samples per observation (long gaps are not
    // filled in at 50 ms).
    const sim::Trajectory walked = sim::smooth_track(tr);
    if (walked.samples().size() > 45 * tr.samples().size() + 2) std::abort();
    for (const auto& s : walked.samples()) {
      if (!std::isfinite(s.pose.x_m) || !std::isfinite(s.pose.y_m) ||
          !std::isfinite(s.pose.theta_rad)) {
        std::abort();
      }
    }
  }
  return 0;
}
