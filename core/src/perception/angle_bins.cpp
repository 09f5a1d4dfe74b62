#include "core/perception/angle_bins.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/util/floor_to_int.hpp"

namespace core {
namespace {

constexpr double kPi = std::numbers::pi;
// Farther than this from a boundary, the formula's rounding (atan2's last bit, the addition and
// the division: ~1e-15 rad) cannot move a direction into the next bin.
constexpr double kMarginRad = 1e-10;

// atan(t) for |t| <= 1 to within 1.5e-3 rad: only a first guess of the bin (a bin is >= 8.7e-3
// rad wide here), which the exact tests then confirm or move by one.
double atan_guess(double t) {
  const double a = std::abs(t);
  return t * (std::numbers::pi / 4.0) - t * (a - 1.0) * (0.2447 + 0.0663 * a);
}

}  // namespace

AzimuthBins::AzimuthBins(int bins)
    : bins_(bins),
      width_rad_(2.0 * kPi / bins),
      inv_width_(1.0 / width_rad_),
      cos_(static_cast<size_t>(bins) + 1),
      sin_(static_cast<size_t>(bins) + 1) {
  for (int k = 0; k <= bins; ++k) {
    const double a = -kPi + k * width_rad_;
    cos_[static_cast<size_t>(k)] = std::cos(a);
    sin_[static_cast<size_t>(k)] = std::sin(a);
  }
}

int AzimuthBins::bin_by_atan2(double x, double y) const {
  return static_cast<int>(floor_to_int((std::atan2(y, x) + kPi) / width_rad_)) % bins_;
}

int AzimuthBins::side(int k, double x, double y) const {
  // |v| sin(angle from boundary k to v): |v| <= |x| + |y| scales the margin.
  const double s = cos_[static_cast<size_t>(k)] * y - sin_[static_cast<size_t>(k)] * x;
  const double margin = kMarginRad * (std::abs(x) + std::abs(y));
  return s > margin ? 1 : (s < -margin ? -1 : 0);  // NaN: 0 (undecided)
}

int AzimuthBins::bin(double x, double y) const {
  const double ax = std::abs(x);
  const double ay = std::abs(y);
  if (!(ax + ay > 0.0) || !(ax + ay < 1e300)) return bin_by_atan2(x, y);  // zero, NaN, infinite
  double guess = 0.0;
  if (ax >= ay) {
    const double a = atan_guess(y / x);
    guess = x > 0.0 ? a : (y >= 0.0 ? a + kPi : a - kPi);
  } else {
    guess = (y > 0.0 ? kPi / 2.0 : -kPi / 2.0) - atan_guess(x / y);
  }
  auto k = static_cast<int>(floor_to_int((guess + kPi) * inv_width_));
  k = k < 0 ? bins_ - 1 : (k >= bins_ ? 0 : k);
  // The guess is within one bin: confirm it, or step once (across -pi / pi if need be).
  for (int tries = 0; tries < 2; ++tries) {
    const int lower = side(k, x, y);
    const int upper = side(k + 1, x, y);
    if (lower == 0 || upper == 0) break;  // on a boundary: the formula decides
    if (lower > 0 && upper < 0) return k;
    k += lower < 0 ? -1 : 1;
    k = k < 0 ? bins_ - 1 : (k >= bins_ ? 0 : k);
  }
  return bin_by_atan2(x, y);
}

int AzimuthBins::bin(double x, double y, int hint) const {
  if (hint >= 0 && hint < bins_ && side(hint, x, y) > 0 && side(hint + 1, x, y) < 0) return hint;
  return bin(x, y);
}

ElevationBins::ElevationBins(double width_rad)
    : width_rad_(width_rad),
      inv_width_(1.0 / width_rad),
      max_bin_(static_cast<int64_t>(kPi / 2.0 / width_rad) - 1),
      tan_(static_cast<size_t>(2 * max_bin_ + 1)),
      margin_(tan_.size()) {
  for (int64_t k = -max_bin_; k <= max_bin_; ++k) {
    const double t = std::tan(static_cast<double>(k) * width_rad);
    tan_[static_cast<size_t>(k + max_bin_)] = t;
    margin_[static_cast<size_t>(k + max_bin_)] = kMarginRad * (1.0 + t * t);  // d tan = sec^2
  }
}

int64_t ElevationBins::bin_by_atan2(double z, double h) const {
  return floor_to_int(std::atan2(z, h) / width_rad_);
}

int64_t ElevationBins::bin(double z, double h) const {
  if (max_bin_ < 1 || !(h > 0.0)) return bin_by_atan2(z, h);  // bins of 45 degrees or more
  const double r = z / h;
  if (!(std::abs(r) < tan_.back())) return bin_by_atan2(z, h);  // beyond the table, or NaN
  const double guess =
      std::abs(r) <= 1.0 ? atan_guess(r) : (r > 0.0 ? kPi / 2.0 : -kPi / 2.0) - atan_guess(1.0 / r);
  int64_t k = std::clamp<int64_t>(floor_to_int(guess * inv_width_), -max_bin_, max_bin_ - 1);
  for (int tries = 0; tries < 2; ++tries) {
    const auto lo = static_cast<size_t>(k + max_bin_);
    const double below = r - tan_[lo];
    const double above = tan_[lo + 1] - r;
    if (std::abs(below) <= margin_[lo] || std::abs(above) <= margin_[lo + 1]) break;
    if (below > 0.0 && above > 0.0) return k;
    k += below < 0.0 ? -1 : 1;
    if (k < -max_bin_ || k >= max_bin_) break;
  }
  return bin_by_atan2(z, h);
}

int64_t ElevationBins::bin(double z, double h, int64_t hint) const {
  if (h > 0.0 && hint >= -max_bin_ && hint < max_bin_) {
    // z / h against the bin's tangents, multiplied out (h > 0): no division.
    const auto lo = static_cast<size_t>(hint + max_bin_);
    if (z - h * tan_[lo] > h * margin_[lo] && h * tan_[lo + 1] - z > h * margin_[lo + 1]) {
      return hint;
    }
  }
  return bin(z, h);
}

}  // namespace core
