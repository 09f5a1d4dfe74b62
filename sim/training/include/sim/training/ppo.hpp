#pragma once
// PPO (Schulman et al. 2017) for the learned selector, with skrl 1.x's defaults as the paper
// used them (reference/evaluation.md, "PPO"): rollouts of 16 steps per environment, 8 learning
// epochs of 2 mini-batches, discount 0.99, GAE lambda 0.95, Adam at 1e-3 under skrl's
// KL-adaptive schedule (target 0.008: /1.5 above twice the target, x1.5 below half of it, in
// [1e-6, 1e-2]), ratio clip 0.2, gradient-norm clip 0.5, no entropy bonus, value loss scale 1,
// advantages normalised over the rollout. Actor 256-128-64 (ReLU) -> n logits, masked to P
// before the softmax; a critic of the same shape -> 1. Observations are standardised by a
// running mean and deviation (frozen into the policy file). LibTorch, one thread.
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "core/policy/mlp_policy.hpp"

namespace sim::training {

// What the trainer needs of an environment (FollowEnv, and small test problems).
class Environment {
 public:
  virtual ~Environment() = default;
  [[nodiscard]] virtual size_t observation_size() const = 0;
  [[nodiscard]] virtual int actions() const = 0;
  virtual void reset(std::span<float> observation, std::span<bool> mask) = 0;
  struct Outcome {
    double reward = 0;
    bool terminated = false;  // no value after this step
    bool truncated = false;   // time limit (the next observation starts a new episode)
  };
  // Writes the next observation (the first of a new episode after a terminal step).
  virtual Outcome step(int action, std::span<float> observation, std::span<bool> mask) = 0;
};

struct PpoConfig {
  int rollout_steps = 16;  // per environment
  int epochs = 8;
  int minibatches = 2;
  double discount = 0.99;
  double gae_lambda = 0.95;
  double learning_rate = 1e-3;
  double kl_target = 0.008;
  double lr_min = 1e-6, lr_max = 1e-2, lr_factor = 1.5;
  double ratio_clip = 0.2;
  double grad_norm_clip = 0.5;
  double entropy_scale = 0.0;
  double value_loss_scale = 1.0;
  double reward_scale = 0.01;  // rewards x this for the critic (r_collision = -200 -> -2)
  std::vector<int> hidden = {256, 128, 64};
  double std_floor = 0.1;  // the standardiser's smallest deviation (a feature constant in
                           // training must not blow up when it moves at run time)
  uint64_t seed = 1;
};

// GAE(lambda) over a rollout of T steps x N environments (row t, column e: index t * N + e).
// `done[t*N+e]`: the episode ended at step t (no bootstrap past it). `last_values`: V of the
// observation after the rollout. Writes advantages and returns (= advantages + values).
void compute_gae(std::span<const float> rewards, std::span<const float> values,
                 std::span<const uint8_t> done, std::span<const float> last_values, int steps,
                 int envs, double discount, double lambda, std::span<float> advantages,
                 std::span<float> returns);

struct UpdateStats {
  uint64_t env_steps = 0;
  double learning_rate = 0;
  double kl = 0;
  double policy_loss = 0, value_loss = 0;
  double mean_reward = 0;  // per step, in the environment's units
};

class PpoTrainer {
 public:
  PpoTrainer(const PpoConfig& config, std::vector<Environment*> envs);
  ~PpoTrainer();
  PpoTrainer(const PpoTrainer&) = delete;
  PpoTrainer& operator=(const PpoTrainer&) = delete;

  // One rollout and one learning phase.
  UpdateStats update();
  // Supervised warm start (optional): `rollouts` rollouts labelled with `teacher`'s choice, then
  // the masked actor refit (cross-entropy) on every sample gathered so far. Who acts:
  // `kTeacher` (behaviour cloning: the teacher's own states) or `kLearner` (DAgger, Ross et al.
  // 2011: the learner's greedy choices drive the environments, so it also learns what the
  // teacher would do in the states its own mistakes lead to). The standardiser fits every
  // sample too. The samples stay in memory (4 bytes per observation value: ~2.9 kB each with
  // the daemon's 716-value observation, ~300 MB for the 102 400 of docs/EVALUATION.md's run).
  enum class Driver { kTeacher, kLearner };
  struct ImitationStats {
    size_t new_samples = 0, samples = 0;
    double agreement = 0;     // of the new samples: the learner's greedy choice was the teacher's
                              // (before this refit; the on-policy match DAgger improves)
    double fit_accuracy = 0;  // on every sample, after the refit
  };
  ImitationStats imitate(const std::function<int(size_t env)>& teacher, int rollouts,
                         Driver driver = Driver::kTeacher);
  // Off: updates train the critic only; the actor, the standardiser and the learning-rate
  // schedule (which reads the actor's KL) stay as they are: a warm-started actor keeps its
  // choices while the value function catches up with it.
  void set_actor_learning(bool on);

  // The greedy (masked argmax) choice for one raw observation.
  int act_greedy(std::span<const float> observation, std::span<const bool> mask);
  // The actor as a policy file for the daemon (core/policy/mlp_policy.hpp).
  [[nodiscard]] core::PolicyFile export_policy(uint32_t layout_id) const;
  // Raw logits of the actor (tests compare them with core::MlpPolicy on the exported file).
  std::vector<float> logits(std::span<const float> observation);
  // The critic's value of one raw observation (in reward_scale units).
  double value(std::span<const float> observation);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sim::training
