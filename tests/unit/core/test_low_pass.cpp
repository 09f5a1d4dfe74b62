// core::LowPass2 (core/util/low_pass.hpp).
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <random>

#include "core/util/low_pass.hpp"

using namespace std::chrono_literals;

namespace {
// Sample i of a 30 Hz stream.
core::Nanos at_30hz(int i) {
  return std::chrono::duration_cast<core::Nanos>(std::chrono::duration<double>(i / 30.0));
}
}  // namespace

TEST(LowPass, TheFirstSamplePassesThenAStepRisesAtTheTimeConstant) {
  core::LowPass2 f(0.5);
  EXPECT_FALSE(f.primed());
  EXPECT_DOUBLE_EQ(f.update({1.0, -2.0}, at_30hz(0)).x_m, 1.0) << "no history: no lag";
  // A step from (1, -2) to (2, 0), sampled at 30 Hz for 0.5 s: 1 - 1/e of the way.
  core::Point2 y;
  for (int i = 1; i <= 15; ++i)
    y = f.update({2.0, 0.0}, at_30hz(i));
  EXPECT_NEAR(y.x_m, 1.0 + (1.0 - std::exp(-1.0)), 1e-9);
  EXPECT_NEAR(y.y_m, -2.0 + 2.0 * (1.0 - std::exp(-1.0)), 1e-9);
  // The same 0.5 s in one sample: the same value (independent of the rate).
  core::LowPass2 g(0.5);
  g.update({1.0, -2.0}, 0ms);
  EXPECT_NEAR(g.update({2.0, 0.0}, 500ms).x_m, y.x_m, 1e-9);
  f.reset();
  EXPECT_DOUBLE_EQ(f.update({5.0, 5.0}, 1s).x_m, 5.0) << "reset: no history again";
  EXPECT_DOUBLE_EQ(f.update({7.0, 5.0}, 900ms).x_m, 5.0) << "time going back: held";
  core::LowPass2 off(0.0);
  off.update({1.0, 1.0}, 0ms);
  EXPECT_DOUBLE_EQ(off.update({3.0, 1.0}, 100ms).x_m, 3.0);
}

TEST(LowPass, NoiseIsReducedAndTheMeanKept) {
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.1);
  core::LowPass2 f(0.5);
  double raw2 = 0.0, out2 = 0.0, mean = 0.0;
  const int n = 3000;
  for (int i = 0; i < n; ++i) {
    const double x = 1.0 + noise(rng);
    const double y = f.update({x, 0.0}, at_30hz(i)).x_m;
    if (i < 100) continue;
    raw2 += (x - 1.0) * (x - 1.0);
    out2 += (y - 1.0) * (y - 1.0);
    mean += y;
  }
  EXPECT_NEAR(mean / (n - 100), 1.0, 0.01);
  EXPECT_LT(std::sqrt(out2 / raw2), 0.25) << "white noise at 30 Hz through 0.5 s: ~0.18 of it";
}
