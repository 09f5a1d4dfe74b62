// The policy file format and the MLP runtime: a tiny policy generated here, inference compared
// with an independent computation, and every validation error.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>

#include "core/policy/mlp_policy.hpp"

namespace {

constexpr uint32_t kLayout = 7;
constexpr uint32_t kPoints = 4;
constexpr uint32_t kInput = 6;

core::PolicyFile tiny(uint32_t seed = 1) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> n(0.0f, 0.7f);
  core::PolicyFile p;
  p.layout_id = kLayout;
  p.points = kPoints;
  p.mean = Eigen::VectorXf::Zero(kInput);
  p.stddev = Eigen::VectorXf::Ones(kInput);
  for (uint32_t i = 0; i < kInput; ++i) {
    p.mean[i] = 0.1f * static_cast<float>(i);
    p.stddev[i] = 1.0f + 0.5f * static_cast<float>(i);
  }
  const std::array<std::pair<int, core::Activation>, 3> shape = {
      {{5, core::Activation::kRelu}, {3, core::Activation::kTanh}, {4, core::Activation::kNone}}};
  int in = kInput;
  for (const auto& [out, act] : shape) {
    core::DenseLayer l;
    l.weights.resize(out, in);
    l.bias.resize(out);
    for (int r = 0; r < out; ++r) {
      for (int c = 0; c < in; ++c)
        l.weights(r, c) = n(rng);
      l.bias[r] = n(rng);
    }
    l.activation = act;
    p.layers.push_back(l);
    in = out;
  }
  return p;
}

// The same network, computed with plain loops in double precision.
std::vector<double> reference(const core::PolicyFile& p, const std::vector<float>& obs) {
  std::vector<double> x(obs.size());
  for (size_t i = 0; i < obs.size(); ++i) {
    x[i] =
        (static_cast<double>(obs[i]) - static_cast<double>(p.mean[static_cast<Eigen::Index>(i)])) /
        static_cast<double>(p.stddev[static_cast<Eigen::Index>(i)]);
  }
  for (const auto& l : p.layers) {
    std::vector<double> y(static_cast<size_t>(l.weights.rows()));
    for (Eigen::Index r = 0; r < l.weights.rows(); ++r) {
      double s = static_cast<double>(l.bias[r]);
      for (Eigen::Index c = 0; c < l.weights.cols(); ++c) {
        s += static_cast<double>(l.weights(r, c)) * x[static_cast<size_t>(c)];
      }
      if (l.activation == core::Activation::kRelu) s = std::max(0.0, s);
      if (l.activation == core::Activation::kTanh) s = std::tanh(s);
      y[static_cast<size_t>(r)] = s;
    }
    x = y;
  }
  return x;
}

core::PolicyLoadResult parse(const std::vector<uint8_t>& b) {
  return core::parse_policy(b, kLayout, kPoints, kInput);
}

TEST(MlpPolicy, InferenceMatchesAnIndependentComputation) {
  const auto bytes = core::encode_policy(tiny());
  const auto loaded = parse(bytes);
  ASSERT_TRUE(loaded.policy) << loaded.error;
  core::MlpPolicy policy(*loaded.policy);
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> u(-3.0f, 3.0f);
  for (int trial = 0; trial < 50; ++trial) {
    std::vector<float> obs(kInput);
    for (auto& v : obs)
      v = u(rng);
    const auto expected = reference(*loaded.policy, obs);
    const Eigen::VectorXf& z = policy.logits(obs);
    ASSERT_EQ(z.size(), 4);
    for (int i = 0; i < 4; ++i)
      EXPECT_NEAR(z[i], expected[static_cast<size_t>(i)], 1e-5);
    // The masked argmax: the best among the allowed points only.
    const std::array<bool, 4> mask = {true, false, true, true};
    int best = -1;
    for (int i = 0; i < 4; ++i) {
      if (mask[static_cast<size_t>(i)] &&
          (best < 0 || expected[static_cast<size_t>(i)] > expected[static_cast<size_t>(best)])) {
        best = i;
      }
    }
    EXPECT_EQ(policy.select(obs, mask), best);
  }
  const std::array<bool, 4> none = {false, false, false, false};
  EXPECT_EQ(policy.select(std::vector<float>(kInput, 0.0f), none), -1);
}

TEST(MlpPolicy, EncodeParseRoundTripsAndIsDeterministic) {
  const auto a = core::encode_policy(tiny(3));
  const auto loaded = parse(a);
  ASSERT_TRUE(loaded.policy) << loaded.error;
  EXPECT_EQ(core::encode_policy(*loaded.policy), a);
  core::MlpPolicy p1(*loaded.policy);
  core::MlpPolicy p2(*loaded.policy);
  const std::vector<float> obs = {0.3f, -1.0f, 2.0f, 0.0f, 1.5f, -0.2f};
  EXPECT_EQ(p1.logits(obs), p2.logits(obs));
}

TEST(MlpPolicy, EveryValidationErrorIsClear) {
  const auto good = core::encode_policy(tiny());
  auto expect_error = [](const core::PolicyLoadResult& r, const std::string& text) {
    ASSERT_FALSE(r.policy);
    EXPECT_NE(r.error.find(text), std::string::npos) << r.error;
  };
  auto bad = good;
  bad[0] = 'X';
  expect_error(parse(bad), "magic");
  bad = good;
  bad[8] = 2;
  expect_error(parse(bad), "format version 2");
  expect_error(core::parse_policy(good, kLayout + 1, kPoints, kInput),
               "observation layout id 7, the runtime builds 8");
  expect_error(core::parse_policy(good, kLayout, 64, kInput), "trained for n = 4");
  expect_error(core::parse_policy(good, kLayout, kPoints, 7), "input size 6");
  // Every truncation fails cleanly.
  for (size_t cut = 0; cut < good.size(); ++cut) {
    const auto r = parse(std::vector<uint8_t>(good.begin(), good.begin() + static_cast<long>(cut)));
    ASSERT_FALSE(r.policy) << cut;
  }
  bad = good;
  bad.push_back(0);
  expect_error(parse(bad), "1 bytes after the last layer");
  // A NaN weight, a zero standard deviation, a broken chain, an unknown activation.
  auto p = tiny();
  p.layers[1].weights(0, 0) = std::nanf("");
  expect_error(parse(core::encode_policy(p)), "layer 1: weights are not all finite");
  p = tiny();
  p.stddev[2] = 0.0f;
  expect_error(parse(core::encode_policy(p)), "standard deviation of input 2");
  p = tiny();
  p.layers[2].weights.resize(4, 2);  // expects 3 inputs
  expect_error(parse(core::encode_policy(p)), "layer 2: input 2 does not follow");
  p = tiny();
  p.layers[0].activation = static_cast<core::Activation>(9);
  expect_error(parse(core::encode_policy(p)), "unknown activation 9");
  p = tiny();
  p.layers.pop_back();
  expect_error(parse(core::encode_policy(p)), "the last layer has 3 outputs, n = 4");
}

TEST(MlpPolicy, LoadsFromAFileAndNamesItInErrors) {
  const std::string path = ::testing::TempDir() + "tiny.policy";
  const auto bytes = core::encode_policy(tiny());
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()),
             static_cast<std::streamsize>(bytes.size()));
  EXPECT_TRUE(core::load_policy_file(path, kLayout, kPoints, kInput).policy);
  const auto r = core::load_policy_file(path, kLayout, 64, kInput);
  EXPECT_NE(r.error.find(path), std::string::npos) << r.error;
  EXPECT_NE(core::load_policy_file("/nonexistent.policy", kLayout, kPoints, kInput)
                .error.find("cannot read /nonexistent.policy"),
            std::string::npos);
  (void)std::remove(path.c_str());
}

}  // namespace
