// The angle bins must equal the plain atan2 formula bit for bit (the voxel grid's seen-through
// pass and, through it, every evaluation table depend on the bins): on random directions of every
// length, on the boundaries themselves and one ulp either side of them, on the axes and at -pi /
// pi, and beyond the elevation table.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "core/perception/angle_bins.hpp"

namespace {

constexpr double kPi = std::numbers::pi;

// (x, y) and its neighbours one ulp away in each coordinate.
template <typename F>
void with_neighbours(double x, double y, F&& check) {
  for (const double xx : {std::nextafter(x, -1e300), x, std::nextafter(x, 1e300)}) {
    for (const double yy : {std::nextafter(y, -1e300), y, std::nextafter(y, 1e300)})
      check(xx, yy);
  }
}

TEST(AngleBins, AzimuthEqualsTheAtan2FormulaEverywhere) {
  const core::AzimuthBins bins(720);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> angle(-kPi, kPi);
  std::uniform_real_distribution<double> log_length(-6.0, 3.0);
  for (int i = 0; i < 400000; ++i) {
    const double a = angle(rng);
    const double r = std::pow(10.0, log_length(rng));
    const double x = r * std::cos(a), y = r * std::sin(a);
    const int exact = bins.bin_by_atan2(x, y);
    ASSERT_EQ(bins.bin(x, y), exact) << x << " " << y;
    // With a hint: right, one off, far off, out of range.
    for (const int hint : {exact, exact + 1, exact - 1, exact + 300, -1, 720}) {
      ASSERT_EQ(bins.bin(x, y, hint), exact) << x << " " << y << " hint " << hint;
    }
  }
  // Every boundary, at several lengths, and one ulp around it.
  for (int k = 0; k <= 720; ++k) {
    const double a = -kPi + k * (2.0 * kPi / 720.0);
    for (const double r : {1e-4, 0.37, 1.0, 6.0, 250.0}) {
      with_neighbours(r * std::cos(a), r * std::sin(a), [&](double x, double y) {
        const int exact = bins.bin_by_atan2(x, y);
        ASSERT_EQ(bins.bin(x, y), exact) << k << " " << x << " " << y;
        ASSERT_EQ(bins.bin(x, y, k % 720), exact) << k << " " << x << " " << y;
        ASSERT_EQ(bins.bin(x, y, (k + 719) % 720), exact) << k << " " << x << " " << y;
      });
    }
  }
  // Axes, signed zeros and the -pi / pi seam.
  for (const double x : {-2.0, -0.0, 0.0, 2.0}) {
    for (const double y : {-2.0, -1e-300, -0.0, 0.0, 1e-300, 2.0})
      EXPECT_EQ(bins.bin(x, y), bins.bin_by_atan2(x, y)) << x << " " << y;
  }
}

TEST(AngleBins, ElevationEqualsTheAtan2FormulaEverywhere) {
  const core::ElevationBins bins(kPi / 180.0);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> angle(-kPi / 2.0, kPi / 2.0);
  std::uniform_real_distribution<double> log_length(-6.0, 3.0);
  for (int i = 0; i < 400000; ++i) {
    const double a = angle(rng);
    const double r = std::pow(10.0, log_length(rng));
    const double h = r * std::cos(a), z = r * std::sin(a);
    const int64_t exact = bins.bin_by_atan2(z, h);
    ASSERT_EQ(bins.bin(z, h), exact) << z << " " << h;
    for (const int64_t hint : {exact, exact + 1, exact - 1, exact + 40, int64_t{-89}, int64_t{88},
                               int64_t{200}, int64_t{-200}}) {
      ASSERT_EQ(bins.bin(z, h, hint), exact) << z << " " << h << " hint " << hint;
    }
  }
  // Every whole degree from -90 to 90 (the table ends at 89), and one ulp around it.
  for (int k = -90; k <= 90; ++k) {
    const double a = k * (kPi / 180.0);
    for (const double r : {1e-4, 0.8, 9.0}) {
      with_neighbours(r * std::sin(a), r * std::cos(a), [&](double z, double h) {
        const int64_t exact = bins.bin_by_atan2(z, h);
        ASSERT_EQ(bins.bin(z, h), exact) << k << " " << z << " " << h;
        ASSERT_EQ(bins.bin(z, h, k), exact) << k << " " << z << " " << h;
        ASSERT_EQ(bins.bin(z, h, k - 1), exact) << k << " " << z << " " << h;
      });
    }
  }
  for (const double z : {-1.0, -0.0, 0.0, 1.0, 1e6, -1e6}) {
    for (const double h : {-1.0, 0.0, 1e-300, 1.0})
      EXPECT_EQ(bins.bin(z, h), bins.bin_by_atan2(z, h)) << z << " " << h;
    for (const double h : {-1.0, 0.0, 1e-300, 1.0})
      EXPECT_EQ(bins.bin(z, h, 0), bins.bin_by_atan2(z, h)) << z << " " << h;
  }
}

}  // namespace
