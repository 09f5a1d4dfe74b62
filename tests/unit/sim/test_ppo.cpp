// PPO (sim/training/ppo.hpp): GAE against a hand computation, the exported policy file equal to
// the trained actor in the daemon's runtime, learning a masked choice it starts ignorant of, and
// the warm start: behaviour cloning, DAgger, a frozen actor while the critic learns.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "core/policy/mlp_policy.hpp"
#include "sim/training/ppo.hpp"

using sim::training::Environment;
using sim::training::PpoConfig;
using sim::training::PpoTrainer;

namespace {

// One-step episodes: the observation says (one-hot, with noise) which of 4 actions pays 1; one
// other action is masked. A policy that ignores the observation is right 1 time in 3.
class MaskedBandit final : public Environment {
 public:
  explicit MaskedBandit(uint64_t seed) : rng_(seed) {}
  [[nodiscard]] size_t observation_size() const override { return 6; }
  [[nodiscard]] int actions() const override { return 4; }
  void reset(std::span<float> o, std::span<bool> m) override { draw(o, m); }
  Outcome step(int a, std::span<float> o, std::span<bool> m) override {
    const double reward = a == target_ ? 1.0 : 0.0;
    ++steps_;
    if (a != target_) ++off_target_;
    draw(o, m);
    return {reward, true, false};
  }
  int target() const { return target_; }
  int masked() const { return masked_; }
  int steps() const { return steps_; }
  int off_target() const { return off_target_; }  // steps that acted on another action

 private:
  void draw(std::span<float> o, std::span<bool> m) {
    target_ = static_cast<int>(rng_() % 4);
    masked_ = (target_ + 1 + static_cast<int>(rng_() % 3)) % 4;
    std::normal_distribution<float> noise(0.0f, 0.1f);
    for (size_t i = 0; i < 4; ++i)
      o[i] = (static_cast<int>(i) == target_ ? 1.0f : 0.0f) + noise(rng_);
    o[4] = 3.0f + noise(rng_);  // an offset the standardiser removes
    o[5] = 0.0f;                // a constant (the deviation's floor keeps it finite)
    for (size_t i = 0; i < 4; ++i)
      m[i] = static_cast<int>(i) != masked_;
  }
  std::mt19937_64 rng_;
  int target_ = 0, masked_ = 1;
  int steps_ = 0, off_target_ = 0;
};

// n bandits seeded from `first_seed`, and the trainer's view of them.
struct Bandits {
  Bandits(int n, uint64_t first_seed) {
    for (int i = 0; i < n; ++i)
      envs.emplace_back(first_seed + static_cast<uint64_t>(i));
    for (auto& e : envs)
      list.push_back(&e);
  }
  std::vector<MaskedBandit> envs;
  std::vector<Environment*> list;
};

double greedy_accuracy(PpoTrainer& trainer, MaskedBandit& env, int trials, int* masked_picks) {
  std::vector<float> o(6);
  bool mb[4] = {};
  std::span<bool> m(mb);
  env.reset(o, m);
  int right = 0;
  for (int i = 0; i < trials; ++i) {
    const int a = trainer.act_greedy(o, m);
    if (a == env.masked()) ++*masked_picks;
    if (a == env.target()) ++right;
    env.step(a, o, m);
  }
  return static_cast<double>(right) / trials;
}

}  // namespace

TEST(Ppo, GeneralisedAdvantageEstimateByHand) {
  // 3 steps, 1 environment, the episode ends after step 1; discount 0.9, lambda 0.5.
  const std::vector<float> rewards{1, 2, 3}, values{0.5f, 1.0f, 2.0f}, last{4.0f};
  const std::vector<uint8_t> done{0, 1, 0};
  std::vector<float> adv(3), ret(3);
  sim::training::compute_gae(rewards, values, done, last, 3, 1, 0.9, 0.5, adv, ret);
  const double d2 = 3 + 0.9 * 4 - 2.0;  // bootstraps on the value after the rollout
  const double d1 = 2 - 1.0;            // terminal: no bootstrap
  const double d0 = 1 + 0.9 * 1.0 - 0.5;
  EXPECT_NEAR(static_cast<double>(adv[2]), d2, 1e-5);
  EXPECT_NEAR(static_cast<double>(adv[1]), d1, 1e-5);
  EXPECT_NEAR(static_cast<double>(adv[0]), d0 + 0.9 * 0.5 * d1, 1e-5);
  EXPECT_NEAR(static_cast<double>(ret[0]), static_cast<double>(adv[0]) + 0.5, 1e-5);
  // Two interleaved environments (row t * N + e) do not mix.
  const std::vector<float> r2{1, 10, 0, 0}, v2{0, 0, 0, 0}, last2{0, 0};
  const std::vector<uint8_t> done2{0, 0, 1, 1};
  std::vector<float> adv2(4), ret2(4);
  sim::training::compute_gae(r2, v2, done2, last2, 2, 2, 1.0, 1.0, adv2, ret2);
  EXPECT_NEAR(adv2[0], 1.0, 1e-6);
  EXPECT_NEAR(adv2[1], 10.0, 1e-6);
}

TEST(Ppo, LearnsAMaskedChoiceItStartsIgnorantOf) {
  Bandits bandits(8, 100);
  PpoConfig config;
  config.hidden = {32, 32};
  config.reward_scale = 1.0;
  config.seed = 3;
  PpoTrainer trainer(config, bandits.list);
  MaskedBandit probe(999);
  int masked = 0;
  const double before = greedy_accuracy(trainer, probe, 300, &masked);
  for (int u = 0; u < 150; ++u)
    trainer.update();
  const double after = greedy_accuracy(trainer, probe, 300, &masked);
  EXPECT_LT(before, 0.6);
  EXPECT_GT(after, 0.95);
  EXPECT_EQ(masked, 0) << "the greedy choice never takes a masked action";
}

TEST(Ppo, TheExportedFileIsTheActorInTheDaemonsRuntime) {
  Bandits bandits(4, 200);
  PpoConfig config;
  config.hidden = {16, 8};
  PpoTrainer trainer(config, bandits.list);
  for (int u = 0; u < 5; ++u)
    trainer.update();  // weights and standardiser away from the start

  const auto bytes = core::encode_policy(trainer.export_policy(1));
  auto loaded = core::parse_policy(bytes, 1, 4, 6);
  ASSERT_TRUE(loaded.policy) << loaded.error;
  ASSERT_EQ(loaded.policy->layers.size(), 3U);
  EXPECT_EQ(loaded.policy->layers[0].activation, core::Activation::kRelu);
  EXPECT_EQ(loaded.policy->layers[2].activation, core::Activation::kNone);
  core::MlpPolicy runtime(std::move(*loaded.policy));
  std::mt19937 rng(5);
  std::normal_distribution<float> n(0.0f, 2.0f);
  for (int k = 0; k < 20; ++k) {
    std::vector<float> o(6);
    for (float& v : o)
      v = n(rng);
    const auto expected = trainer.logits(o);
    const auto& got = runtime.logits(o);
    ASSERT_EQ(got.size(), 4);
    for (int a = 0; a < 4; ++a)
      EXPECT_NEAR(got[a], expected[static_cast<size_t>(a)], 1e-4);
    const bool mask[4] = {true, k % 2 == 0, true, false};
    EXPECT_EQ(runtime.select(o, mask), trainer.act_greedy(o, mask));
  }
}

TEST(Ppo, ImitationCopiesTheTeachersMaskedChoice) {
  Bandits bandits(8, 300);
  PpoConfig config;
  config.hidden = {32, 32};
  PpoTrainer trainer(config, bandits.list);
  MaskedBandit probe(998);
  int masked = 0;
  const double before = greedy_accuracy(trainer, probe, 300, &masked);
  const auto stats = trainer.imitate([&](size_t e) { return bandits.envs[e].target(); }, 20);
  const double after = greedy_accuracy(trainer, probe, 300, &masked);
  EXPECT_EQ(stats.samples, 20U * 16U * 8U);
  EXPECT_GT(stats.fit_accuracy, 0.95);
  EXPECT_LT(before, 0.6);
  EXPECT_GT(after, 0.95);
  EXPECT_EQ(masked, 0);
  for (const auto& env : bandits.envs)
    EXPECT_EQ(env.off_target(), 0) << "behaviour cloning: the teacher's choices drive";
}

TEST(Ppo, DaggerLetsTheLearnerDriveAndKeepsEverySample) {
  using Driver = PpoTrainer::Driver;
  Bandits bandits(8, 400);
  PpoConfig config;
  config.hidden = {32, 32};
  PpoTrainer trainer(config, bandits.list);
  const auto teacher = [&](size_t e) { return bandits.envs[e].target(); };
  // An untrained learner drives: it acts off the teacher's choice about 2 times in 3, and its
  // agreement before the fit says so.
  const auto first = trainer.imitate(teacher, 4, Driver::kLearner);
  int off = 0, steps = 0;
  for (const auto& env : bandits.envs) {
    off += env.off_target();
    steps += env.steps();
  }
  EXPECT_EQ(steps, 4 * 16 * 8);
  EXPECT_GT(off, steps / 3);
  EXPECT_NEAR(first.agreement, 1.0 - static_cast<double>(off) / steps, 1e-9);
  // The next round keeps the first's samples and learns from both; the refit learner agrees.
  const auto second = trainer.imitate(teacher, 16, Driver::kLearner);
  EXPECT_EQ(second.new_samples, 16U * 16U * 8U);
  EXPECT_EQ(second.samples, first.samples + second.new_samples);
  EXPECT_GT(second.agreement, first.agreement);
  EXPECT_GT(second.fit_accuracy, 0.95);
}

TEST(Ppo, AFrozenActorKeepsItsChoicesWhileTheCriticLearns) {
  Bandits bandits(8, 500);
  PpoConfig config;
  config.hidden = {32, 32};
  config.reward_scale = 1.0;
  PpoTrainer trainer(config, bandits.list);
  trainer.update();  // a standardiser and weights away from the start
  const std::vector<float> probe{1.0f, 0.0f, 0.0f, 0.0f, 3.0f, 0.0f};
  const auto logits_before = trainer.logits(probe);
  const double value_before = trainer.value(probe);
  trainer.set_actor_learning(false);
  for (int u = 0; u < 10; ++u)
    trainer.update();
  EXPECT_EQ(trainer.logits(probe), logits_before) << "actor and standardiser frozen";
  EXPECT_GT(std::abs(trainer.value(probe) - value_before), 1e-3) << "the critic learnt";
  trainer.set_actor_learning(true);
  for (int u = 0; u < 10; ++u)
    trainer.update();
  EXPECT_NE(trainer.logits(probe), logits_before);
}
