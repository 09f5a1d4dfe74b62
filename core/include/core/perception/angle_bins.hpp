#pragma once
// The bin of a direction's angle, bit for bit what the plain formula with std::atan2 gives, in
// about half its time (less with a hint: a scan's returns come in order): the bin is guessed,
// then decided by exact side-of-boundary tests against tabulated boundaries. A direction within
// 1e-10 rad of a boundary, where atan2's last bit could decide, takes the formula itself. The
// voxel grid's seen-through pass bins every ray and every occupied voxel this way (atan2 was an
// eighth of the lidar cycle), and the evaluation's tables depend on those bins bit for bit: a
// cheaper atan2 with another rounding would move them.
#include <cstdint>
#include <vector>

namespace core {

// Azimuth bins over the circle from -pi: floor((atan2(y, x) + pi) / (2 pi / bins)) % bins.
class AzimuthBins {
 public:
  explicit AzimuthBins(int bins);
  [[nodiscard]] int bin(double x, double y) const;
  // The same, trying `hint` first (the bin of a direction just before, e.g. the previous return
  // of a scan): two boundary tests instead of the guess, when the direction is still in it.
  [[nodiscard]] int bin(double x, double y, int hint) const;
  // The formula with std::atan2: the reference, and the path near a boundary.
  [[nodiscard]] int bin_by_atan2(double x, double y) const;

 private:
  // Side of (x, y) against boundary k (counter-clockwise positive), or 0 when it is within the
  // margin of it (undecided).
  [[nodiscard]] int side(int k, double x, double y) const;

  int bins_;
  double width_rad_;
  double inv_width_;               // the guess multiplies (the formula itself divides)
  std::vector<double> cos_, sin_;  // boundary k at -pi + k width, k = 0..bins
};

// Elevation bins of a direction (z up, h > 0 its horizontal length): floor(atan2(z, h) / width),
// signed (bin 0 is [0, width)).
class ElevationBins {
 public:
  explicit ElevationBins(double width_rad);
  [[nodiscard]] int64_t bin(double z, double h) const;
  [[nodiscard]] int64_t bin(double z, double h, int64_t hint) const;  // as AzimuthBins's
  [[nodiscard]] int64_t bin_by_atan2(double z, double h) const;

 private:
  double width_rad_;
  double inv_width_;
  int64_t max_bin_;             // bins -max_bin .. max_bin - 1 are tabulated (below 90 degrees)
  std::vector<double> tan_;     // tan(k width), k = -max_bin .. max_bin
  std::vector<double> margin_;  // the ratio's margin around boundary k: 1e-10 rad in angle
};

}  // namespace core
