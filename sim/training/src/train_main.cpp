// companion-train: PPO training of the learned selector in the training environment
// (sim/training/follow_env.hpp), written as a policy file companiond reads (policy.file).
// Optional build: cmake -DCOMPANION_BUILD_TRAINING=ON (needs libtorch-dev).
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/policy/observation.hpp"
#include "firmware/config/config_loader.hpp"
#include "sim/training/follow_env.hpp"
#include "sim/training/ppo.hpp"

namespace {

using sim::training::FollowEnv;
using sim::training::FollowEnvConfig;

class FollowEnvironment final : public sim::training::Environment {
 public:
  FollowEnvironment(const FollowEnvConfig& c, uint64_t seed) : env(c, seed) {}
  [[nodiscard]] size_t observation_size() const override { return env.observation_size(); }
  [[nodiscard]] int actions() const override { return env.points(); }
  void reset(std::span<float> o, std::span<bool> m) override { env.reset(o, m); }
  Outcome step(int a, std::span<float> o, std::span<bool> m) override {
    const auto r = env.step(a, o, m);
    return {r.rewards.total(), r.terminated, r.truncated};
  }
  FollowEnv env;
};

struct EvalResult {
  double mean_return = 0;
  double contact_rate = 0, person_contact_rate = 0, lost_rate = 0;
  double near_obstacle_s = 0;  // per episode
  double jumps_per_min = 0;    // the chosen point moving > 0.3 m between decisions
};

// `episodes` whole episodes on fixed seeds (the same worlds for every call), choosing with
// `choose` (an index into W, or -1).
template <typename Choose>
EvalResult evaluate(const FollowEnvConfig& config, int episodes, uint64_t first_seed,
                    Choose&& choose) {
  EvalResult r;
  double jumps = 0, seconds = 0;
  for (int i = 0; i < episodes; ++i) {
    FollowEnv env(config, first_seed + static_cast<uint64_t>(i));
    std::vector<float> obs(env.observation_size());
    const auto points = static_cast<size_t>(env.points());
    const auto mask_storage = std::make_unique<bool[]>(points);
    const std::span<bool> mask(mask_storage.get(), points);
    env.reset(obs, mask);
    while (env.episodes() == 1) {
      const int a = choose(env, obs, mask);
      const auto s = env.step(a, obs, mask);
      if (s.terminated || s.truncated) break;
    }
    const auto& e = env.last_episode();
    r.mean_return += e.return_sum / episodes;
    r.contact_rate += (e.contact ? 1.0 : 0.0) / episodes;
    r.person_contact_rate += (e.contact_person ? 1.0 : 0.0) / episodes;
    r.lost_rate += (e.lost ? 1.0 : 0.0) / episodes;
    r.near_obstacle_s += e.near_obstacle_s / episodes;
    jumps += e.jumps;
    seconds += e.duration_s;
  }
  r.jumps_per_min = seconds > 0 ? 60.0 * jumps / seconds : 0.0;
  return r;
}

// Writes the policy file whole or not at all (a temporary beside it, then a rename).
bool write_policy(const std::string& path, const std::vector<uint8_t>& bytes) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream f(tmp, std::ios::binary);
    f.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
    if (!f.good()) return false;
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  return !ec;
}

int run(int argc, char** argv) {
  CLI::App app{
      "companion-train: PPO for the learned selector (writes a policy file for policy.file)"};
  std::string out, config_path, log_path;
  uint64_t steps = 200000, seed = 1;
  int envs = 8, imitate_rollouts = 0, eval_every = 25, eval_episodes = 8;
  std::string evaluate_path;
  app.add_option("--out", out, "policy file to write (the best evaluation so far)");
  app.add_option("--evaluate", evaluate_path,
                 "instead of training: run this policy file and the objective selector on the "
                 "evaluation worlds and print both")
      ->check(CLI::ExistingFile);
  app.add_option("-c,--config", config_path,
                 "daemon configuration: the interactive space, objective, limits and costmap")
      ->check(CLI::ExistingFile);
  app.add_option("--steps", steps, "environment steps (policy decisions) to train for");
  app.add_option("--envs", envs, "environments per rollout")->check(CLI::Range(1, 256));
  app.add_option("--seed", seed, "seed of the worlds and of the learner");
  app.add_option("--imitate-rollouts", imitate_rollouts,
                 "warm start: rollouts of the objective selector to imitate first (0: none, "
                 "the paper's from-scratch PPO)");
  int dagger_rounds = 0, critic_warmup = 0;
  app.add_option("--dagger-rounds", dagger_rounds,
                 "after the warm start: rounds of DAgger (the learner drives, the objective "
                 "labels; --imitate-rollouts rollouts each)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--critic-warmup", critic_warmup,
                 "first PPO updates that train the critic only (the warm-started actor frozen)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--eval-every", eval_every, "updates between evaluations")
      ->check(CLI::PositiveNumber);
  app.add_option("--eval-episodes", eval_episodes, "episodes per evaluation (fixed worlds)")
      ->check(CLI::PositiveNumber);
  app.add_option("--log", log_path, "CSV of the training (one row per evaluation)");
  std::string checkpoints;
  app.add_option("--checkpoints", checkpoints,
                 "also write every candidate here (imitation-R.bin after each imitation round, "
                 "update-U.bin at each evaluation) for a choice by closed-loop trials "
                 "(sim/eval/validate_policies.sh)");
  double sigma_h = -1, sigma_a = -1, tracking_distance = -1;
  app.add_option("--sigma-h", sigma_h, "r^h weight per metre closed (default 100)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--sigma-a", sigma_a, "r^a weight per index of W the choice moves (default 0.5)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--tracking-distance", tracking_distance,
                 "D: r_tracking within this distance of the person (the paper's 0.75 m)")
      ->check(CLI::PositiveNumber);
  double dead_end_fraction = 0;
  app.add_option("--dead-end-fraction", dead_end_fraction,
                 "episodes in the dead_end case's corridor instead of a random world (default 0)")
      ->check(CLI::Range(0.0, 1.0));
  sim::training::PpoConfig ppo;
  app.add_option("--entropy", ppo.entropy_scale,
                 "entropy bonus (skrl's default 0; a deterministic policy then has KL 0 and "
                 "the KL-adaptive schedule raises the rate to lr_max)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--lr", ppo.learning_rate, "the first learning rate (skrl: 1e-3)")
      ->check(CLI::PositiveNumber);
  app.add_option("--lr-max", ppo.lr_max, "the KL-adaptive schedule's ceiling (skrl: 1e-2)")
      ->check(CLI::PositiveNumber);
  app.add_option("--rollout-steps", ppo.rollout_steps,
                 "steps per environment per update (skrl: 16)")
      ->check(CLI::Range(2, 4096));
  CLI11_PARSE(app, argc, argv);

  const auto loaded = config_path.empty() ? firmware::load_default_config()
                                          : firmware::load_config_file(config_path);
  if (!loaded.ok()) {
    for (const auto& e : loaded.errors)
      fmt::print(stderr, "{}\n", e.to_string());
    return 2;
  }
  FollowEnvConfig env_config = sim::training::follow_env_config(*loaded.config);
  if (sigma_h >= 0) env_config.reward.sigma_h_per_m = sigma_h;
  if (sigma_a >= 0) env_config.reward.sigma_a_per_index = sigma_a;
  if (tracking_distance > 0) env_config.reward.tracking_distance_m = tracking_distance;
  env_config.dead_end_probability = dead_end_fraction;

  if (dagger_rounds > 0 && imitate_rollouts <= 0) {
    fmt::print(stderr, "--dagger-rounds needs --imitate-rollouts (the rollouts of each round)\n");
    return 2;
  }
  if (out.empty() && evaluate_path.empty()) {
    fmt::print(stderr, "--out is required (or --evaluate FILE)\n");
    return 2;
  }
  if (!checkpoints.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(checkpoints, ec);
    if (ec || !std::filesystem::is_directory(checkpoints)) {
      fmt::print(stderr, "--checkpoints {}: cannot make the directory ({})\n", checkpoints,
                 ec.message());
      return 2;
    }
  }
  const uint64_t eval_seed = 9000000;
  auto print_eval = [](const char* who, const EvalResult& r) {
    fmt::print(
        "{}: return {:.0f}, contact {:.0f} % (the person {:.0f} %), lost {:.0f} %, near "
        "obstacles {:.1f} s, q^d jumps {:.1f} per minute\n",
        who, r.mean_return, 100 * r.contact_rate, 100 * r.person_contact_rate, 100 * r.lost_rate,
        r.near_obstacle_s, r.jumps_per_min);
  };
  const auto objective = [](FollowEnv& env, auto&, auto&) { return env.objective_action(); };
  if (!evaluate_path.empty()) {
    const auto n = static_cast<uint32_t>(env_config.space.points);
    auto file = core::load_policy_file(evaluate_path, core::kObservationLayout, n,
                                       static_cast<uint32_t>(core::observation_size(n)));
    if (!file.policy) {
      fmt::print(stderr, "{}: {}\n", evaluate_path, file.error);
      return 2;
    }
    core::MlpPolicy policy(std::move(*file.policy));
    print_eval("objective", evaluate(env_config, eval_episodes, eval_seed, objective));
    print_eval(evaluate_path.c_str(),
               evaluate(env_config, eval_episodes, eval_seed,
                        [&](FollowEnv&, std::vector<float>& obs, std::span<bool> mask) {
                          return policy.select(obs, mask);
                        }));
    return 0;
  }

  // Worlds: training seeds from 1 000 000 (the benchmark uses 1-50, validation 101-180);
  // evaluation worlds from 9 000 000.
  std::vector<std::unique_ptr<FollowEnvironment>> owned;
  std::vector<sim::training::Environment*> list;
  for (int i = 0; i < envs; ++i) {
    owned.push_back(std::make_unique<FollowEnvironment>(
        env_config, 1000000 + seed * 1000 + static_cast<uint64_t>(i)));
    list.push_back(owned.back().get());
  }
  ppo.seed = seed;
  sim::training::PpoTrainer trainer(ppo, list);

  std::ofstream log;
  if (!log_path.empty()) {
    log.open(log_path);
    if (!log) {
      fmt::print(stderr, "cannot write {}\n", log_path);
      return 2;
    }
    log << "update,env_steps,wall_s,learning_rate,kl,mean_reward,eval_return,"
           "eval_contact_rate,eval_person_contact_rate,eval_lost_rate,eval_near_obstacle_s,"
           "eval_jumps_per_min\n";
  }
  const auto t0 = std::chrono::steady_clock::now();
  auto wall = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  };

  const EvalResult baseline = evaluate(env_config, eval_episodes, eval_seed, objective);
  fmt::print(
      "objective selector on {} evaluation worlds: return {:.0f}, contact {:.0f} % (the person "
      "{:.0f} %), lost {:.0f} %, near obstacles {:.1f} s\n",
      eval_episodes, baseline.mean_return, 100 * baseline.contact_rate,
      100 * baseline.person_contact_rate, 100 * baseline.lost_rate, baseline.near_obstacle_s);
  auto greedy = [&](FollowEnv&, std::vector<float>& obs, std::span<bool> mask) {
    return trainer.act_greedy(obs, mask);
  };
  // The training return chooses --out; the checkpoints let closed-loop trials choose instead
  // (the return is not what the benchmark counts: twelfth version, docs/EVALUATION.md).
  auto policy_bytes = [&] {
    return core::encode_policy(trainer.export_policy(core::kObservationLayout));
  };
  auto checkpoint = [&](const std::string& name) {
    if (checkpoints.empty()) return;
    const auto path = (std::filesystem::path(checkpoints) / (name + ".bin")).string();
    if (!write_policy(path, policy_bytes()))
      throw std::runtime_error("cannot write the checkpoint " + path);
  };
  double best = -1e300;
  auto save = [&](double score, int update) {
    if (score <= best) return;
    best = score;
    if (!write_policy(out, policy_bytes()))
      throw std::runtime_error("cannot write the policy file " + out);
    fmt::print("  wrote {} (update {}, evaluation return {:.0f})\n", out, update, score);
  };

  if (imitate_rollouts > 0) {
    const auto teacher = [&](size_t e) { return owned[e]->env.objective_action(); };
    for (int round = 0; round <= dagger_rounds; ++round) {
      using Driver = sim::training::PpoTrainer::Driver;
      const auto st = trainer.imitate(teacher, imitate_rollouts,
                                      round == 0 ? Driver::kTeacher : Driver::kLearner);
      const std::string agreement =
          round == 0 ? std::string("the objective drove")
                     : fmt::format(
                           "the learner chose the objective's point in {:.1f} % of its "
                           "own states before the fit",
                           100 * st.agreement);
      fmt::print(
          "imitation round {} ({}): {} samples, {}, {:.1f} % of all after the fit ({:.0f} "
          "s)\n",
          round, round == 0 ? "behaviour cloning" : "DAgger", st.samples, agreement,
          100 * st.fit_accuracy, wall());
      checkpoint(fmt::format("imitation-{}", round));
    }
    // The warm-started policy is a candidate too: PPO's checkpoints replace it only by doing
    // better on the evaluation worlds.
    const EvalResult r = evaluate(env_config, eval_episodes, eval_seed, greedy);
    print_eval("imitation", r);
    save(r.mean_return, 0);
  }
  trainer.set_actor_learning(critic_warmup <= 0);

  int update = 0;
  uint64_t done_steps = 0;
  while (done_steps < steps) {
    const auto s = trainer.update();
    done_steps = s.env_steps;
    ++update;
    if (update == critic_warmup) trainer.set_actor_learning(true);
    if (update % eval_every == 0 || done_steps >= steps) {
      const EvalResult r = evaluate(env_config, eval_episodes, eval_seed, greedy);
      fmt::print(
          "update {:5d}  steps {:8d}  {:6.0f} s  lr {:.1e}  kl {:.4f}  reward/step {:7.2f}  "
          "eval return {:7.0f} (objective {:.0f})  contact {:3.0f} % (the person {:3.0f} %)  lost "
          "{:3.0f} %\n",
          update, done_steps, wall(), s.learning_rate, s.kl, s.mean_reward, r.mean_return,
          baseline.mean_return, 100 * r.contact_rate, 100 * r.person_contact_rate,
          100 * r.lost_rate);
      std::fflush(stdout);  // NOLINT(cert-err33-c): progress lines, nothing to do on failure
      if (log.is_open()) {
        log << fmt::format(
                   "{},{},{:.1f},{:.3g},{:.5f},{:.3f},{:.1f},{:.3f},{:.3f},{:.3f},{:.2f},{:.1f}\n",
                   update, done_steps, wall(), s.learning_rate, s.kl, s.mean_reward, r.mean_return,
                   r.contact_rate, r.person_contact_rate, r.lost_rate, r.near_obstacle_s,
                   r.jumps_per_min)
            << std::flush;
      }
      save(r.mean_return, update);
      checkpoint(fmt::format("update-{:05d}", update));
    }
  }
  fmt::print("done: {} steps in {:.0f} s ({:.0f} steps/s)\n", done_steps, wall(),
             static_cast<double>(done_steps) / wall());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    fmt::print(stderr, "companion-train: {}\n", e.what());
    return 1;
  }
}
