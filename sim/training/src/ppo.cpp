// The only translation unit with <torch/torch.h> besides the trainer's tests (each costs ~20 s
// and ~1.2 GB to compile).
#include "sim/training/ppo.hpp"

#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <stdexcept>

namespace sim::training {
namespace {

// A ReLU MLP; the last layer has no activation.
struct MlpImpl : torch::nn::Module {
  MlpImpl(int64_t in, const std::vector<int>& hidden, int64_t out, double last_gain) {
    int64_t prev = in;
    for (size_t i = 0; i <= hidden.size(); ++i) {
      const int64_t width = i < hidden.size() ? hidden[i] : out;
      layers.push_back(register_module("fc" + std::to_string(i), torch::nn::Linear(prev, width)));
      prev = width;
    }
    // A near-uniform first policy (and a near-zero first value): the usual PPO initialisation.
    torch::NoGradGuard no_grad;
    layers.back()->weight.mul_(last_gain);
    layers.back()->bias.zero_();
  }
  torch::Tensor forward(torch::Tensor x) {
    for (size_t i = 0; i + 1 < layers.size(); ++i)
      x = torch::relu(layers[i]->forward(x));
    return layers.back()->forward(x);
  }
  std::vector<torch::nn::Linear> layers;
};
TORCH_MODULE(Mlp);

// Running mean and variance of the observations (Chan et al.'s parallel update), like skrl's
// RunningStandardScaler; frozen into the exported file.
struct Standardiser {
  explicit Standardiser(size_t width) : mean(width, 0.0), m2(width, 0.0) {}
  void add(const float* rows, size_t count, size_t width) {
    if (count == 0) return;
    std::vector<double> bm(width, 0.0), bv(width, 0.0);
    for (size_t r = 0; r < count; ++r) {
      for (size_t j = 0; j < width; ++j)
        bm[j] += static_cast<double>(rows[r * width + j]);
    }
    for (double& v : bm)
      v /= static_cast<double>(count);
    for (size_t r = 0; r < count; ++r) {
      for (size_t j = 0; j < width; ++j) {
        const double d = static_cast<double>(rows[r * width + j]) - bm[j];
        bv[j] += d * d;
      }
    }
    const double na = n, nb = static_cast<double>(count), total = na + nb;
    for (size_t j = 0; j < width; ++j) {
      const double delta = bm[j] - mean[j];
      mean[j] += delta * nb / total;
      m2[j] += bv[j] + delta * delta * na * nb / total;
    }
    n = total;
  }
  [[nodiscard]] double stddev(size_t j, double floor) const {
    return n > 1 ? std::max(std::sqrt(m2[j] / n), floor) : 1.0;
  }
  double n = 0;
  std::vector<double> mean, m2;
};

}  // namespace

void compute_gae(std::span<const float> rewards, std::span<const float> values,
                 std::span<const uint8_t> done, std::span<const float> last_values, int steps,
                 int envs, double discount, double lambda, std::span<float> advantages,
                 std::span<float> returns) {
  for (int e = 0; e < envs; ++e) {
    double gae = 0;
    for (int t = steps - 1; t >= 0; --t) {
      const size_t i = static_cast<size_t>(t) * static_cast<size_t>(envs) + static_cast<size_t>(e);
      const double next_value =
          static_cast<double>(t == steps - 1 ? last_values[static_cast<size_t>(e)]
                                             : values[i + static_cast<size_t>(envs)]);
      const double not_done = done[i] != 0 ? 0.0 : 1.0;
      const double value = static_cast<double>(values[i]);
      const double delta =
          static_cast<double>(rewards[i]) + discount * next_value * not_done - value;
      gae = delta + discount * lambda * not_done * gae;
      advantages[i] = static_cast<float>(gae);
      returns[i] = static_cast<float>(gae + value);
    }
  }
}

struct PpoTrainer::Impl {
  Impl(const PpoConfig& c, std::vector<Environment*> e)
      : config(c),
        envs(std::move(e)),
        obs_size(envs.front()->observation_size()),
        actions(envs.front()->actions()),
        actor(static_cast<int64_t>(obs_size), c.hidden, actions, 0.01),
        critic(static_cast<int64_t>(obs_size), c.hidden, 1, 1.0),
        scaler(obs_size),
        rng(c.seed) {
    for (Environment* env : envs) {
      if (env->observation_size() != obs_size || env->actions() != actions) {
        throw std::invalid_argument("environments differ in observation or action size");
      }
    }
    params = actor->parameters();
    for (const auto& p : critic->parameters())
      params.push_back(p);
    lr = std::clamp(config.learning_rate, config.lr_min, config.lr_max);
    optimizer = std::make_unique<torch::optim::Adam>(params, torch::optim::AdamOptions(lr));
    critic_params = critic->parameters();
    critic_optimizer =
        std::make_unique<torch::optim::Adam>(critic_params, torch::optim::AdamOptions(lr));
    const size_t n = envs.size();
    obs.assign(n * obs_size, 0.0f);
    mask = std::make_unique<bool[]>(n * static_cast<size_t>(actions));
    for (size_t i = 0; i < n; ++i)
      reset_env(i);
  }

  void reset_env(size_t i) {
    envs[i]->reset(std::span<float>(&obs[i * obs_size], obs_size), mask_of(i));
  }
  std::span<bool> mask_of(size_t i) {
    return {&mask[i * static_cast<size_t>(actions)], static_cast<size_t>(actions)};
  }

  // Standardised observations of `rows` raw rows as a tensor.
  torch::Tensor standardise(const float* raw, size_t rows) const {
    auto x = torch::from_blob(const_cast<float*>(raw),
                              {static_cast<int64_t>(rows), static_cast<int64_t>(obs_size)},
                              torch::kFloat32)
                 .clone();
    std::vector<float> m(obs_size), s(obs_size);
    for (size_t j = 0; j < obs_size; ++j) {
      m[j] = static_cast<float>(scaler.n > 0 ? scaler.mean[j] : 0.0);
      s[j] = static_cast<float>(scaler.stddev(j, config.std_floor));
    }
    const auto mt = torch::from_blob(m.data(), {static_cast<int64_t>(obs_size)}, torch::kFloat32);
    const auto st = torch::from_blob(s.data(), {static_cast<int64_t>(obs_size)}, torch::kFloat32);
    return (x - mt) / st;
  }
  torch::Tensor mask_tensor(const uint8_t* m, size_t rows) const {
    return torch::from_blob(const_cast<uint8_t*>(m),
                            {static_cast<int64_t>(rows), static_cast<int64_t>(actions)},
                            torch::kUInt8)
        .to(torch::kBool)
        .clone();
  }
  static torch::Tensor masked(const torch::Tensor& logits, const torch::Tensor& m) {
    // A row with no allowed action keeps every logit (the environment falls back on its own).
    const auto any = m.any(1, true);
    const auto allowed = torch::logical_or(m, torch::logical_not(any));
    return logits.masked_fill(torch::logical_not(allowed), -1e9);
  }

  int sample(const float* probs) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    double r = u(rng), acc = 0;
    for (int a = 0; a < actions; ++a) {
      acc += static_cast<double>(probs[a]);
      if (r <= acc) return a;
    }
    for (int a = actions - 1; a >= 0; --a)
      if (probs[a] > 0) return a;
    return 0;
  }

  PpoConfig config;
  std::vector<Environment*> envs;
  size_t obs_size;
  int actions;
  Mlp actor, critic;
  Standardiser scaler;
  std::vector<torch::Tensor> params;  // the actor's and the critic's, in one optimiser
  std::unique_ptr<torch::optim::Adam> optimizer;
  // The critic's alone, while the actor is frozen (the shared optimiser's momentum would go on
  // moving an actor it has trained, even with no gradient).
  std::vector<torch::Tensor> critic_params;
  std::unique_ptr<torch::optim::Adam> critic_optimizer;
  double lr;
  std::mt19937_64 rng;
  std::vector<float> obs;        // current raw observation per environment
  std::unique_ptr<bool[]> mask;  // current mask per environment
  uint64_t env_steps = 0;
  bool actor_learning = true;
  // Every imitation sample so far (raw observation, mask, the teacher's choice).
  std::vector<float> bc_raw;
  std::vector<uint8_t> bc_masks;
  std::vector<int64_t> bc_targets;
};

PpoTrainer::PpoTrainer(const PpoConfig& config, std::vector<Environment*> envs) {
  if (envs.empty()) throw std::invalid_argument("PPO needs at least one environment");
  torch::set_num_threads(1);
  torch::manual_seed(config.seed);
  impl_ = std::make_unique<Impl>(config, std::move(envs));
  // Start the standardiser on the first observations.
  impl_->scaler.add(impl_->obs.data(), impl_->envs.size(), impl_->obs_size);
}

PpoTrainer::~PpoTrainer() = default;

UpdateStats PpoTrainer::update() {
  Impl& m = *impl_;
  const int steps = m.config.rollout_steps;
  const int env_count = static_cast<int>(m.envs.size());
  const size_t rows = static_cast<size_t>(steps) * static_cast<size_t>(env_count);
  const size_t action_count = static_cast<size_t>(m.actions);
  std::vector<float> raw(rows * m.obs_size);
  std::vector<uint8_t> masks(rows * action_count);
  std::vector<int64_t> acts(rows);
  std::vector<float> logp(rows), values(rows), rewards(rows),
      last_values(static_cast<size_t>(env_count));
  std::vector<uint8_t> done(rows);
  double reward_sum = 0;
  {
    torch::NoGradGuard no_grad;
    for (int t = 0; t < steps; ++t) {
      const size_t base = static_cast<size_t>(t) * static_cast<size_t>(env_count);
      std::copy(m.obs.begin(), m.obs.end(),
                raw.begin() + static_cast<ptrdiff_t>(base * m.obs_size));
      std::copy(m.mask.get(), m.mask.get() + static_cast<size_t>(env_count) * action_count,
                masks.begin() + static_cast<ptrdiff_t>(base * action_count));
      const auto x = m.standardise(m.obs.data(), static_cast<size_t>(env_count));
      const auto logits =
          Impl::masked(m.actor->forward(x),
                       m.mask_tensor(&masks[base * action_count], static_cast<size_t>(env_count)));
      const auto lp = torch::log_softmax(logits, 1).contiguous();
      const auto probs = lp.exp().contiguous();
      const auto v = m.critic->forward(x).squeeze(1).contiguous();
      for (int e = 0; e < env_count; ++e) {
        const size_t i = base + static_cast<size_t>(e);
        const int a = m.sample(probs.data_ptr<float>() + static_cast<size_t>(e) * action_count);
        acts[i] = a;
        logp[i] =
            lp.data_ptr<float>()[static_cast<size_t>(e) * action_count + static_cast<size_t>(a)];
        values[i] = v.data_ptr<float>()[e];
        const auto out = m.envs[static_cast<size_t>(e)]->step(
            a, std::span<float>(&m.obs[static_cast<size_t>(e) * m.obs_size], m.obs_size),
            m.mask_of(static_cast<size_t>(e)));
        rewards[i] = static_cast<float>(out.reward * m.config.reward_scale);
        reward_sum += out.reward;
        done[i] = (out.terminated || out.truncated) ? 1 : 0;
      }
    }
    const auto x = m.standardise(m.obs.data(), static_cast<size_t>(env_count));
    const auto v = m.critic->forward(x).squeeze(1).contiguous();
    std::copy(v.data_ptr<float>(), v.data_ptr<float>() + env_count, last_values.begin());
  }
  m.env_steps += rows;

  std::vector<float> adv(rows), ret(rows);
  compute_gae(rewards, values, done, last_values, steps, env_count, m.config.discount,
              m.config.gae_lambda, adv, ret);
  // Normalised advantages over the rollout.
  const double mean = std::accumulate(adv.begin(), adv.end(), 0.0) / static_cast<double>(rows);
  double var = 0;
  for (float a : adv)
    var += (static_cast<double>(a) - mean) * (static_cast<double>(a) - mean);
  const double sd = std::sqrt(var / static_cast<double>(rows)) + 1e-8;
  for (float& a : adv)
    a = static_cast<float>((static_cast<double>(a) - mean) / sd);

  const auto obs_all = m.standardise(raw.data(), rows);
  const auto mask_all = m.mask_tensor(masks.data(), rows);
  const auto act_t =
      torch::from_blob(acts.data(), {static_cast<int64_t>(rows)}, torch::kInt64).clone();
  const auto old_logp =
      torch::from_blob(logp.data(), {static_cast<int64_t>(rows)}, torch::kFloat32).clone();
  const auto adv_t =
      torch::from_blob(adv.data(), {static_cast<int64_t>(rows)}, torch::kFloat32).clone();
  const auto ret_t =
      torch::from_blob(ret.data(), {static_cast<int64_t>(rows)}, torch::kFloat32).clone();

  UpdateStats stats;
  const int64_t batch = static_cast<int64_t>(rows) / m.config.minibatches;
  std::vector<int64_t> order(rows);
  for (int epoch = 0; epoch < m.config.epochs; ++epoch) {
    std::iota(order.begin(), order.end(), 0);
    std::shuffle(order.begin(), order.end(), m.rng);
    double kl_sum = 0;
    int kl_count = 0;
    for (int b = 0; b < m.config.minibatches; ++b) {
      const auto idx = torch::from_blob(order.data() + b * batch, {batch}, torch::kInt64).clone();
      const auto x = obs_all.index_select(0, idx);
      const auto lp_all =
          torch::log_softmax(Impl::masked(m.actor->forward(x), mask_all.index_select(0, idx)), 1);
      const auto a = act_t.index_select(0, idx);
      const auto new_logp = lp_all.gather(1, a.unsqueeze(1)).squeeze(1);
      const auto log_ratio = new_logp - old_logp.index_select(0, idx);
      const auto ratio = log_ratio.exp();
      const auto ad = adv_t.index_select(0, idx);
      const auto surrogate = torch::min(
          ratio * ad,
          torch::clamp(ratio, 1.0 - m.config.ratio_clip, 1.0 + m.config.ratio_clip) * ad);
      const auto policy_loss = -surrogate.mean();
      const auto value = m.critic->forward(x).squeeze(1);
      const auto value_loss =
          m.config.value_loss_scale * torch::mse_loss(value, ret_t.index_select(0, idx));
      // A frozen actor: the critic's loss alone, stepped by the critic's own optimiser.
      auto loss = m.actor_learning ? policy_loss + value_loss : value_loss;
      if (m.actor_learning && m.config.entropy_scale > 0) {
        const auto p = lp_all.exp();
        const auto entropy = -(p * lp_all.clamp_min(-1e8)).sum(1).mean();
        loss = loss - m.config.entropy_scale * entropy;
      }
      auto& optimizer = m.actor_learning ? *m.optimizer : *m.critic_optimizer;
      optimizer.zero_grad();
      loss.backward();
      torch::nn::utils::clip_grad_norm_(m.actor_learning ? m.params : m.critic_params,
                                        m.config.grad_norm_clip);
      optimizer.step();
      {
        torch::NoGradGuard no_grad;
        kl_sum += ((ratio - 1) - log_ratio).mean().item<double>();
        ++kl_count;
      }
      stats.policy_loss = policy_loss.item<double>();
      stats.value_loss = value_loss.item<double>();
    }
    // skrl's KLAdaptiveLR, once per epoch on the epoch's mean KL.
    const double kl = kl_sum / std::max(kl_count, 1);
    stats.kl = kl;
    // (A frozen actor's KL is 0 by construction: the schedule would only raise the rate.)
    if (m.actor_learning && kl > 2.0 * m.config.kl_target) {
      m.lr = std::max(m.config.lr_min, m.lr / m.config.lr_factor);
    } else if (m.actor_learning && kl > 0 && kl < 0.5 * m.config.kl_target) {
      m.lr = std::min(m.config.lr_max, m.lr * m.config.lr_factor);
    }
    for (auto* opt : {m.optimizer.get(), m.critic_optimizer.get()}) {
      for (auto& group : opt->param_groups()) {
        static_cast<torch::optim::AdamOptions&>(group.options()).lr(m.lr);
      }
    }
  }
  // The standardiser learns from this rollout for the next one (the rollout and its learning
  // phase saw the same statistics); not while the actor is frozen (its input would move).
  if (m.actor_learning) m.scaler.add(raw.data(), rows, m.obs_size);
  stats.env_steps = m.env_steps;
  stats.learning_rate = m.lr;
  stats.mean_reward = reward_sum / static_cast<double>(rows);
  return stats;
}

PpoTrainer::ImitationStats PpoTrainer::imitate(const std::function<int(size_t env)>& teacher,
                                               int rollouts, Driver driver) {
  Impl& m = *impl_;
  const size_t env_count = m.envs.size();
  const size_t action_count = static_cast<size_t>(m.actions);
  const size_t first_new = m.bc_targets.size();
  size_t agreed = 0;
  std::vector<int> learner(env_count, -1);
  std::vector<uint8_t> current_mask(env_count * action_count);
  for (int r = 0; r < rollouts * m.config.rollout_steps; ++r) {
    if (driver == Driver::kLearner) {
      torch::NoGradGuard no_grad;
      std::copy(m.mask.get(), m.mask.get() + env_count * action_count, current_mask.begin());
      const auto greedy = Impl::masked(m.actor->forward(m.standardise(m.obs.data(), env_count)),
                                       m.mask_tensor(current_mask.data(), env_count))
                              .argmax(1)
                              .contiguous();
      for (size_t e = 0; e < env_count; ++e)
        learner[e] = static_cast<int>(greedy.data_ptr<int64_t>()[e]);
    }
    for (size_t e = 0; e < env_count; ++e) {
      const int label = teacher(e);
      if (label >= 0) {
        m.bc_raw.insert(m.bc_raw.end(), m.obs.begin() + static_cast<ptrdiff_t>(e * m.obs_size),
                        m.obs.begin() + static_cast<ptrdiff_t>((e + 1) * m.obs_size));
        for (size_t a = 0; a < action_count; ++a)
          m.bc_masks.push_back(m.mask[e * action_count + a] ? 1 : 0);
        m.bc_targets.push_back(label);
        if (learner[e] == label) ++agreed;
      }
      const int act = driver == Driver::kLearner ? learner[e] : label;
      m.envs[e]->step(act, std::span<float>(&m.obs[e * m.obs_size], m.obs_size), m.mask_of(e));
    }
  }
  m.env_steps += static_cast<uint64_t>(rollouts * m.config.rollout_steps) * env_count;
  ImitationStats stats;
  stats.samples = m.bc_targets.size();
  stats.new_samples = stats.samples - first_new;
  if (stats.samples == 0) return stats;
  if (driver == Driver::kLearner && stats.new_samples > 0) {
    stats.agreement = static_cast<double>(agreed) / static_cast<double>(stats.new_samples);
  }
  m.scaler.add(m.bc_raw.data() + first_new * m.obs_size, stats.new_samples, m.obs_size);
  const size_t rows = stats.samples;
  const auto obs_all = m.standardise(m.bc_raw.data(), rows);
  const auto mask_all = m.mask_tensor(m.bc_masks.data(), rows);
  const auto target_all =
      torch::from_blob(m.bc_targets.data(), {static_cast<int64_t>(rows)}, torch::kInt64).clone();
  torch::optim::Adam opt(m.actor->parameters(), torch::optim::AdamOptions(1e-3));
  const int64_t batch = 256;
  std::vector<int64_t> order(rows);
  for (int epoch = 0; epoch < 20; ++epoch) {
    std::iota(order.begin(), order.end(), 0);
    std::shuffle(order.begin(), order.end(), m.rng);
    for (int64_t s = 0; s < static_cast<int64_t>(rows); s += batch) {
      const int64_t len = std::min<int64_t>(batch, static_cast<int64_t>(rows) - s);
      const auto idx = torch::from_blob(order.data() + s, {len}, torch::kInt64).clone();
      const auto logits = Impl::masked(m.actor->forward(obs_all.index_select(0, idx)),
                                       mask_all.index_select(0, idx));
      const auto loss =
          torch::nll_loss(torch::log_softmax(logits, 1), target_all.index_select(0, idx));
      opt.zero_grad();
      loss.backward();
      opt.step();
    }
  }
  torch::NoGradGuard no_grad;
  const auto pred = Impl::masked(m.actor->forward(obs_all), mask_all).argmax(1);
  stats.fit_accuracy = pred.eq(target_all).to(torch::kFloat32).mean().item<double>();
  return stats;
}

void PpoTrainer::set_actor_learning(bool on) {
  impl_->actor_learning = on;
}

double PpoTrainer::value(std::span<const float> observation) {
  Impl& m = *impl_;
  torch::NoGradGuard no_grad;
  return m.critic->forward(m.standardise(observation.data(), 1)).item<double>();
}

std::vector<float> PpoTrainer::logits(std::span<const float> observation) {
  Impl& m = *impl_;
  torch::NoGradGuard no_grad;
  const auto l = m.actor->forward(m.standardise(observation.data(), 1)).contiguous();
  return {l.data_ptr<float>(), l.data_ptr<float>() + m.actions};
}

int PpoTrainer::act_greedy(std::span<const float> observation, std::span<const bool> mask) {
  const auto l = logits(observation);
  int best = -1;
  for (size_t a = 0; a < l.size() && a < mask.size(); ++a) {
    if (mask[a] && (best < 0 || l[a] > l[static_cast<size_t>(best)])) best = static_cast<int>(a);
  }
  return best;
}

core::PolicyFile PpoTrainer::export_policy(uint32_t layout_id) const {
  const Impl& m = *impl_;
  core::PolicyFile f;
  f.layout_id = layout_id;
  f.points = static_cast<uint32_t>(m.actions);
  f.mean.resize(static_cast<Eigen::Index>(m.obs_size));
  f.stddev.resize(static_cast<Eigen::Index>(m.obs_size));
  for (size_t j = 0; j < m.obs_size; ++j) {
    f.mean[static_cast<Eigen::Index>(j)] =
        static_cast<float>(m.scaler.n > 0 ? m.scaler.mean[j] : 0.0);
    f.stddev[static_cast<Eigen::Index>(j)] =
        static_cast<float>(m.scaler.stddev(j, m.config.std_floor));
  }
  for (size_t i = 0; i < m.actor->layers.size(); ++i) {
    const auto& layer = m.actor->layers[i];
    const auto w = layer->weight.detach().contiguous();
    const auto b = layer->bias.detach().contiguous();
    core::DenseLayer d;
    d.weights.resize(w.size(0), w.size(1));
    std::copy(w.data_ptr<float>(), w.data_ptr<float>() + w.numel(), d.weights.data());
    d.bias.resize(b.size(0));
    std::copy(b.data_ptr<float>(), b.data_ptr<float>() + b.numel(), d.bias.data());
    d.activation =
        i + 1 < m.actor->layers.size() ? core::Activation::kRelu : core::Activation::kNone;
    f.layers.push_back(std::move(d));
  }
  return f;
}

}  // namespace sim::training
