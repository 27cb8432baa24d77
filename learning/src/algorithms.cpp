#include <manibench/learning/algorithms.hpp>

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <tuple>

namespace manibench::learning {

// --- options ------------------------------------------------------------------------------

AlgorithmOptions AlgorithmOptions::makeDefaults(const std::string& name, const std::string& mode) {
  AlgorithmOptions o;
  o.name = name;
  // The learning rate and weight decay are ManiSkill-Learn's for the mode.
  // ManiSkill-Learn's configurations decay the weights (5e-6) of every
  // network on point clouds, and in the state mode only BCQ's VAE (its
  // state BC and TD3+BC configurations have none). Here one value serves
  // all of an algorithm's networks: BCQ's critics get its VAE's.
  const bool points = mode != "state";
  if (name == "bc") {
    // ManiSkill-Learn's BC: batch 128, Adam 3e-4 on point clouds, 1e-3 in
    // the state mode (its state configuration). manibench's state-mode
    // results before 2026-11-28 ran 3e-4 with weight decay 5e-6 and no tanh,
    // which did better on the drawer at 10,000 iterations
    // (docs/learning-results.md, "The same sweep in the state mode").
    o.batch_size = 128;
    o.lr = points ? 3e-4 : 1e-3;
    o.weight_decay = points ? 5e-6 : 0;
  } else if (name == "bcq") {
    // Table 7.
    o.batch_size = 64;
    o.lr = 5e-4;
    o.weight_decay = 5e-6;
  } else if (name == "td3bc") {
    // Table 8; the batch is ManiSkill-Learn's (the table gives none).
    o.batch_size = 64;
    o.lr = 5e-4;
    o.weight_decay = points ? 5e-6 : 0;
  } else if (name == "sac") {
    // Table 6: Adam 3e-4, discount 0.95, minibatch 1024, tau 0.005.
    o.batch_size = 1024;
    o.lr = 3e-4;
    o.weight_decay = 0;
    o.gamma = 0.95;
    o.tau = 0.005;
  } else {
    throw LearningError("unknown algorithm '" + name + "' (bc, bcq, td3bc or sac)");
  }
  return o;
}

void AlgorithmOptions::writeYaml(YAML::Node& node) const {
  node["name"] = name;
  node["batch_size"] = batch_size;
  node["lr"] = lr;
  node["weight_decay"] = weight_decay;
  node["gamma"] = gamma;
  node["tau"] = tau;
  node["phi"] = phi;
  node["train_samples"] = train_samples;
  node["eval_samples"] = eval_samples;
  node["lambda"] = lambda;
  node["kl_weight"] = kl_weight;
  node["alpha"] = alpha;
  node["action_noise"] = action_noise;
  node["noise_clip"] = noise_clip;
  node["policy_delay"] = policy_delay;
  node["bc_tanh"] = bc_tanh;
  node["init_temperature"] = init_temperature;
  node["temperature_gradient_log"] = temperature_gradient_log;
  node["tune_temperature"] = tune_temperature;
  node["target_entropy_per_dim"] = target_entropy_per_dim;
  node["log_std_min"] = log_std_min;
  node["log_std_max"] = log_std_max;
  node["target_update_every"] = target_update_every;
}

AlgorithmOptions AlgorithmOptions::readYaml(const YAML::Node& node) {
  AlgorithmOptions o = makeDefaults(node["name"].as<std::string>());
  o.batch_size = node["batch_size"].as<int64_t>();
  o.lr = node["lr"].as<double>();
  o.weight_decay = node["weight_decay"].as<double>();
  o.gamma = node["gamma"].as<double>();
  o.tau = node["tau"].as<double>();
  o.phi = node["phi"].as<double>();
  o.train_samples = node["train_samples"].as<int64_t>();
  o.eval_samples = node["eval_samples"].as<int64_t>();
  o.lambda = node["lambda"].as<double>();
  o.kl_weight = node["kl_weight"].as<double>();
  o.alpha = node["alpha"].as<double>();
  o.action_noise = node["action_noise"].as<double>();
  o.noise_clip = node["noise_clip"].as<double>();
  o.policy_delay = node["policy_delay"].as<int64_t>();
  // Absent from the checkpoints written before SAC: the defaults.
  o.init_temperature = node["init_temperature"].as<double>(o.init_temperature);
  // Absent from the checkpoints written before these options: what they ran.
  o.bc_tanh = node["bc_tanh"].as<bool>(false);
  o.temperature_gradient_log = node["temperature_gradient_log"].as<bool>(node["init_temperature"].IsDefined());
  o.tune_temperature = node["tune_temperature"].as<bool>(o.tune_temperature);
  o.target_entropy_per_dim = node["target_entropy_per_dim"].as<double>(o.target_entropy_per_dim);
  o.log_std_min = node["log_std_min"].as<double>(o.log_std_min);
  o.log_std_max = node["log_std_max"].as<double>(o.log_std_max);
  o.target_update_every = node["target_update_every"].as<int64_t>(o.target_update_every);
  return o;
}

TransitionBatch TransitionBatch::map(const std::function<torch::Tensor(const torch::Tensor&)>& f) const {
  TransitionBatch out;
  out.obs = obs.map(f);
  if (next_obs.state.defined()) out.next_obs = next_obs.map(f);
  out.actions = f(actions);
  if (rewards.defined()) out.rewards = f(rewards);
  if (dones.defined()) out.dones = f(dones);
  return out;
}

TransitionBatch TransitionBatch::to(const torch::Device& device, bool non_blocking) const {
  return map([&](const torch::Tensor& t) { return t.to(device, non_blocking); });
}

// --- the base -----------------------------------------------------------------------------

void softUpdate(torch::nn::Module& target, const torch::nn::Module& source, double tau) {
  torch::NoGradGuard no_grad;
  const std::vector<torch::Tensor> to = target.parameters(), from = source.parameters();
  for (std::size_t i = 0; i < to.size(); ++i) to[i].mul_(1 - tau).add_(from[i], tau);
}

namespace {

bool g_actor_step_freezes_critics = true;

// The networks' parameters stop requiring gradients for its lifetime: an
// actor loss through a critic then computes the critic's input gradient
// (which the actor needs) and not its parameter gradients, a third of the
// critic's backward (SAC at batch 1024, 3 x 256: bench/learning_speed.cpp
// --algorithm sac). The values are unchanged: each parameter gradient is
// its own product, and the critics' optimizer zeroes theirs before use.
class FrozenParameters {
 public:
  explicit FrozenParameters(std::initializer_list<const Network*> networks) {
    if (!g_actor_step_freezes_critics) return;
    for (const Network* network : networks)
      for (torch::Tensor p : network->parameters())
        if (p.requires_grad()) frozen_.push_back(p.requires_grad_(false));
  }
  ~FrozenParameters() {
    for (torch::Tensor& p : frozen_) p.requires_grad_(true);
  }
  FrozenParameters(const FrozenParameters&) = delete;
  FrozenParameters& operator=(const FrozenParameters&) = delete;

 private:
  std::vector<torch::Tensor> frozen_;
};

void copyParameters(torch::nn::Module& target, const torch::nn::Module& source) { softUpdate(target, source, 1.0); }

}  // namespace

void setActorStepFreezesCritics(bool on) { g_actor_step_freezes_critics = on; }

std::shared_ptr<Network> Algorithm::addNetwork(const std::string& name, std::shared_ptr<Network> network,
                                               const torch::Device& device) {
  network->to(device);
  networks_.emplace_back(name, network);
  return network;
}

torch::optim::Adam& Algorithm::addOptimizer(const std::string& name, const std::vector<std::string>& networks) {
  std::vector<torch::Tensor> parameters;
  for (const std::string& n : networks)
    for (const torch::Tensor& p : getNetwork(n)->parameters()) parameters.push_back(p);
  return addTensorOptimizer(name, std::move(parameters));
}

torch::optim::Adam& Algorithm::addTensorOptimizer(const std::string& name, std::vector<torch::Tensor> parameters) {
  auto adam = std::make_unique<torch::optim::Adam>(
      parameters, torch::optim::AdamOptions(options_.lr).weight_decay(options_.weight_decay));
  optimizers_.emplace_back(name, std::move(adam));
  return *optimizers_.back().second;
}

torch::Tensor Algorithm::addParameter(const std::string& name, torch::Tensor value) {
  value.set_requires_grad(true);
  parameters_.emplace_back(name, value);
  return value;
}

torch::Tensor Algorithm::explore(const ObservationBatch&) {
  throw LearningError(options_.name + " is an offline algorithm: it does not explore");
}

std::shared_ptr<Network> Algorithm::getNetwork(const std::string& name) const {
  for (const auto& [n, network] : networks_)
    if (n == name) return network;
  throw LearningError("no network named '" + name + "'");
}

void Algorithm::setStateNormalization(const torch::Tensor& mean, const torch::Tensor& scale) {
  for (const auto& entry : networks_) entry.second->setStateNormalization(mean, scale);
}

void Algorithm::save(torch::serialize::OutputArchive& archive, bool with_optimizers) const {
  for (const auto& [name, network] : networks_) {
    torch::serialize::OutputArchive sub;
    network->save(sub);
    archive.write("net." + name, sub);
  }
  for (const auto& [name, parameter] : parameters_) archive.write("param." + name, parameter);
  if (!with_optimizers) return;
  for (const auto& [name, optimizer] : optimizers_) {
    torch::serialize::OutputArchive sub;
    optimizer->save(sub);
    archive.write("optim." + name, sub);
  }
}

void Algorithm::load(torch::serialize::InputArchive& archive, bool with_optimizers) {
  for (const auto& [name, network] : networks_) {
    torch::serialize::InputArchive sub;
    archive.read("net." + name, sub);
    network->load(sub);
  }
  for (auto& [name, parameter] : parameters_) {
    torch::Tensor saved;
    archive.read("param." + name, saved);
    torch::NoGradGuard no_grad;
    parameter.copy_(saved);
  }
  if (!with_optimizers) return;
  for (const auto& [name, optimizer] : optimizers_) {
    torch::serialize::InputArchive sub;
    archive.read("optim." + name, sub);
    optimizer->load(sub);
  }
}

namespace {

}  // namespace

// Q-networks (obs, a) -> 1: critic1, critic2 and their targets, made in
// that order (the order draws their initial weights), the targets copies.
std::tuple<std::shared_ptr<Network>, std::shared_ptr<Network>, std::shared_ptr<Network>, std::shared_ptr<Network>>
Algorithm::addTwinCritics(const NetOptions& net, const ObservationSpec& spec, const torch::Device& device) {
  const int64_t a = spec.action_dim;
  auto critic1 = addNetwork("critic1", makeNetwork(net, spec, a, 1), device);
  auto critic2 = addNetwork("critic2", makeNetwork(net, spec, a, 1), device);
  auto critic1_target = addNetwork("critic1_target", makeNetwork(net, spec, a, 1), device);
  auto critic2_target = addNetwork("critic2_target", makeNetwork(net, spec, a, 1), device);
  copyParameters(*critic1_target, *critic1);
  copyParameters(*critic2_target, *critic2);
  return {critic1, critic2, critic1_target, critic2_target};
}

namespace {

void step(torch::optim::Adam& optimizer, const torch::Tensor& loss) {
  optimizer.zero_grad();
  loss.backward();
  optimizer.step();
}

// --- BC -----------------------------------------------------------------------------------

class BehaviorCloning : public Algorithm {
 public:
  BehaviorCloning(const AlgorithmOptions& o, const NetOptions& net, const ObservationSpec& spec,
                  const torch::Device& device)
      : Algorithm(o) {
    actor_ = addNetwork("actor", makeNetwork(net, spec, 0, spec.action_dim), device);
    optimizer_ = &addOptimizer("actor", {"actor"});
  }
  bool needsNextObservations() const override { return false; }
  std::vector<std::string> getLossNames() const override { return {"loss"}; }
  torch::Tensor policy(const ObservationBatch& obs) {
    const torch::Tensor out = actor_->forward(obs, {});
    return options_.bc_tanh ? torch::tanh(out) : out;
  }
  std::vector<double> update(const TransitionBatch& batch, int64_t) override {
    actor_->train();
    const torch::Tensor loss = torch::mse_loss(policy(batch.obs), batch.actions);
    step(*optimizer_, loss);
    return {loss.item<double>()};
  }
  torch::Tensor act(const ObservationBatch& obs, at::Generator&) override {
    torch::NoGradGuard no_grad;
    actor_->eval();
    return policy(obs);
  }

 private:
  std::shared_ptr<Network> actor_;
  torch::optim::Adam* optimizer_;
};

// --- TD3+BC -------------------------------------------------------------------------------

class Td3Bc : public Algorithm {
 public:
  Td3Bc(const AlgorithmOptions& o, const NetOptions& net, const ObservationSpec& spec,
        const torch::Device& device)
      : Algorithm(o) {
    const int64_t a = spec.action_dim;
    actor_ = addNetwork("actor", makeNetwork(net, spec, 0, a), device);
    critic1_ = addNetwork("critic1", makeNetwork(net, spec, a, 1), device);
    critic2_ = addNetwork("critic2", makeNetwork(net, spec, a, 1), device);
    actor_target_ = addNetwork("actor_target", makeNetwork(net, spec, 0, a), device);
    critic1_target_ = addNetwork("critic1_target", makeNetwork(net, spec, a, 1), device);
    critic2_target_ = addNetwork("critic2_target", makeNetwork(net, spec, a, 1), device);
    copyParameters(*actor_target_, *actor_);
    copyParameters(*critic1_target_, *critic1_);
    copyParameters(*critic2_target_, *critic2_);
    actor_optimizer_ = &addOptimizer("actor", {"actor"});
    critic_optimizer_ = &addOptimizer("critic", {"critic1", "critic2"});
  }
  bool needsNextObservations() const override { return true; }
  std::vector<std::string> getLossNames() const override {
    return {"critic_loss", "actor_loss", "bc_loss", "q"};
  }
  torch::Tensor policy(Network& actor, const ObservationBatch& obs) {
    return torch::tanh(actor.forward(obs, {}));
  }
  std::vector<double> update(const TransitionBatch& b, int64_t iteration) override {
    for (auto& [name, network] : networks_) network->train();
    torch::Tensor target;
    {
      torch::NoGradGuard no_grad;
      const torch::Tensor noise =
          (torch::randn_like(b.actions) * options_.action_noise).clamp(-options_.noise_clip, options_.noise_clip);
      const torch::Tensor next_action = (policy(*actor_target_, b.next_obs) + noise).clamp(-1, 1);
      const torch::Tensor q_next = torch::min(critic1_target_->forward(b.next_obs, next_action),
                                              critic2_target_->forward(b.next_obs, next_action)).squeeze(1);
      target = b.rewards + options_.gamma * (1 - b.dones) * q_next;
    }
    const torch::Tensor critic_loss =
        torch::mse_loss(critic1_->forward(b.obs, b.actions).squeeze(1), target) +
        torch::mse_loss(critic2_->forward(b.obs, b.actions).squeeze(1), target);
    step(*critic_optimizer_, critic_loss);
    if ((iteration + 1) % options_.policy_delay == 0) {
      const FrozenParameters frozen({critic1_.get()});
      const torch::Tensor pi = policy(*actor_, b.obs);
      const torch::Tensor q = critic1_->forward(b.obs, pi);
      const torch::Tensor lambda = options_.alpha / q.abs().mean().detach().clamp_min(1e-8);
      const torch::Tensor bc = torch::mse_loss(pi, b.actions);
      const torch::Tensor actor_loss = -lambda * q.mean() + bc;
      step(*actor_optimizer_, actor_loss);
      softUpdate(*critic1_target_, *critic1_, options_.tau);
      softUpdate(*critic2_target_, *critic2_, options_.tau);
      softUpdate(*actor_target_, *actor_, options_.tau);
      last_actor_ = actor_loss.item<double>();
      last_bc_ = bc.item<double>();
      last_q_ = q.mean().item<double>();
    }
    return {critic_loss.item<double>(), last_actor_, last_bc_, last_q_};
  }
  torch::Tensor act(const ObservationBatch& obs, at::Generator&) override {
    torch::NoGradGuard no_grad;
    actor_->eval();
    return policy(*actor_, obs);
  }

 private:
  std::shared_ptr<Network> actor_, critic1_, critic2_, actor_target_, critic1_target_, critic2_target_;
  torch::optim::Adam *actor_optimizer_, *critic_optimizer_;
  double last_actor_ = 0, last_bc_ = 0, last_q_ = 0;
};

// --- BCQ ----------------------------------------------------------------------------------

class Bcq : public Algorithm {
 public:
  Bcq(const AlgorithmOptions& o, const NetOptions& net, const ObservationSpec& spec,
      const torch::Device& device)
      : Algorithm(o), action_dim_(spec.action_dim), latent_dim_(2 * spec.action_dim) {
    const int64_t a = action_dim_, z = latent_dim_;
    // The VAE: encoder (obs, a) -> mean and log std of z; decoder (obs, z) -> a.
    encoder_ = addNetwork("vae_encoder", makeNetwork(net, spec, a, 2 * z), device);
    decoder_ = addNetwork("vae_decoder", makeNetwork(net, spec, z, a), device);
    std::tie(critic1_, critic2_, critic1_target_, critic2_target_) = addTwinCritics(net, spec, device);
    vae_optimizer_ = &addOptimizer("vae", {"vae_encoder", "vae_decoder"});
    critic_optimizer_ = &addOptimizer("critic", {"critic1", "critic2"});
    if (o.phi > 0) {
      // The perturbation model xi(obs, a) in [-phi, phi].
      actor_ = addNetwork("actor", makeNetwork(net, spec, a, a), device);
      actor_target_ = addNetwork("actor_target", makeNetwork(net, spec, a, a), device);
      copyParameters(*actor_target_, *actor_);
      actor_optimizer_ = &addOptimizer("actor", {"actor"});
    }
  }
  bool needsNextObservations() const override { return true; }
  std::vector<std::string> getLossNames() const override {
    return {"vae_loss", "recon_loss", "kl_loss", "critic_loss", "actor_loss"};
  }

  torch::Tensor decode(const ObservationBatch& obs, const torch::Tensor& z) {
    return torch::tanh(decoder_->forward(obs, z));
  }
  // The latents come from `generator` (the acting policy's, seeded per
  // episode) or, without one (nullptr), libtorch's default generator of the
  // observations' device. A generator of another device (the policy's CPU
  // one beside networks on CUDA, which at::normal refuses: "Expected a
  // 'cuda' device type for generator") draws on its own device and the
  // draw is moved: the same seed gives the same latents on either device.
  // (A pointer, not an optional: c10::optional is its own class in libtorch
  // 1.13 and std::optional in 2.x.)
  torch::Tensor sampleActions(const ObservationBatch& obs, at::Generator* generator) {
    const torch::TensorOptions options = obs.state.options();
    const std::vector<int64_t> size{obs.size(), latent_dim_};
    torch::Tensor z;
    if (generator == nullptr)
      z = at::normal(0.0, 1.0, size, {}, options);
    else if (generator->device() != options.device())
      z = at::normal(0.0, 1.0, size, *generator, options.device(generator->device())).to(options.device());
    else
      z = at::normal(0.0, 1.0, size, *generator, options);
    return decode(obs, z.clamp(-0.5, 0.5));
  }
  torch::Tensor perturb(Network* actor, const ObservationBatch& obs, const torch::Tensor& a) {
    if (actor == nullptr) return a;
    return (a + options_.phi * torch::tanh(actor->forward(obs, a))).clamp(-1, 1);
  }

  std::vector<double> update(const TransitionBatch& b, int64_t) override {
    for (auto& [name, network] : networks_) network->train();
    // The VAE.
    const torch::Tensor stats = encoder_->forward(b.obs, b.actions);
    const torch::Tensor mean = stats.slice(1, 0, latent_dim_);
    const torch::Tensor log_std = stats.slice(1, latent_dim_).clamp(-4, 15);
    const torch::Tensor std = log_std.exp();
    const torch::Tensor z = mean + std * torch::randn_like(std);
    const torch::Tensor recon_loss = torch::mse_loss(decode(b.obs, z), b.actions);
    const torch::Tensor kl_loss = (-0.5 * (1 + 2 * log_std - mean.pow(2) - std.pow(2))).mean();
    const torch::Tensor vae_loss = recon_loss + options_.kl_weight * kl_loss;
    step(*vae_optimizer_, vae_loss);
    // The critics: the best of n sampled next actions under a soft
    // clipped double Q (lambda min + (1 - lambda) max).
    torch::Tensor target;
    {
      torch::NoGradGuard no_grad;
      const int64_t n = options_.train_samples;
      const ObservationBatch next = b.next_obs.repeatEach(n);
      const torch::Tensor next_action = perturb(actor_target_.get(), next, sampleActions(next, nullptr));
      const torch::Tensor q1 = critic1_target_->forward(next, next_action);
      const torch::Tensor q2 = critic2_target_->forward(next, next_action);
      const torch::Tensor q = options_.lambda * torch::min(q1, q2) + (1 - options_.lambda) * torch::max(q1, q2);
      const torch::Tensor best = std::get<0>(q.view({b.obs.size(), n}).max(1));
      target = b.rewards + options_.gamma * (1 - b.dones) * best;
    }
    const torch::Tensor critic_loss =
        torch::mse_loss(critic1_->forward(b.obs, b.actions).squeeze(1), target) +
        torch::mse_loss(critic2_->forward(b.obs, b.actions).squeeze(1), target);
    step(*critic_optimizer_, critic_loss);
    double actor_value = 0;
    if (actor_) {
      const FrozenParameters frozen({critic1_.get()});
      torch::Tensor sampled;
      {
        torch::NoGradGuard no_grad;
        sampled = sampleActions(b.obs, nullptr);
      }
      const torch::Tensor actor_loss = -critic1_->forward(b.obs, perturb(actor_.get(), b.obs, sampled)).mean();
      step(*actor_optimizer_, actor_loss);
      softUpdate(*actor_target_, *actor_, options_.tau);
      actor_value = actor_loss.item<double>();
    }
    softUpdate(*critic1_target_, *critic1_, options_.tau);
    softUpdate(*critic2_target_, *critic2_, options_.tau);
    return {vae_loss.item<double>(), recon_loss.item<double>(), kl_loss.item<double>(),
            critic_loss.item<double>(), actor_value};
  }

  torch::Tensor act(const ObservationBatch& obs, at::Generator& generator) override {
    torch::NoGradGuard no_grad;
    for (auto& [name, network] : networks_) network->eval();
    const int64_t n = options_.eval_samples, b = obs.size();
    const ObservationBatch many = obs.repeatEach(n);
    const torch::Tensor actions = perturb(actor_.get(), many, sampleActions(many, &generator));
    const torch::Tensor q = critic1_->forward(many, actions).view({b, n});
    const torch::Tensor best = std::get<1>(q.max(1));  // [B]
    const torch::Tensor rows = torch::arange(b, best.options()) * n + best;
    return actions.index_select(0, rows);
  }

 private:
  int64_t action_dim_, latent_dim_;
  std::shared_ptr<Network> encoder_, decoder_, critic1_, critic2_, critic1_target_, critic2_target_;
  std::shared_ptr<Network> actor_, actor_target_;
  torch::optim::Adam *vae_optimizer_, *critic_optimizer_, *actor_optimizer_ = nullptr;
};

// --- SAC ----------------------------------------------------------------------------------

// The actor outputs the mean and log std of a Gaussian over the
// pre-squashing action u; the action is tanh(u) (Haarnoja et al. 2018,
// appendix C), its log-likelihood corrected by log(1 - tanh(u)^2),
// written as 2 (log 2 - u - softplus(-2u)) for stability.
class Sac : public Algorithm {
 public:
  Sac(const AlgorithmOptions& o, const NetOptions& net, const ObservationSpec& spec, const torch::Device& device)
      : Algorithm(o), action_dim_(spec.action_dim) {
    const int64_t a = action_dim_;
    actor_ = addNetwork("actor", makeNetwork(net, spec, 0, 2 * a), device);
    std::tie(critic1_, critic2_, critic1_target_, critic2_target_) = addTwinCritics(net, spec, device);
    actor_optimizer_ = &addOptimizer("actor", {"actor"});
    critic_optimizer_ = &addOptimizer("critic", {"critic1", "critic2"});
    log_temperature_ = addParameter(
        "log_temperature", torch::full({1}, std::log(o.init_temperature), torch::TensorOptions(device)));
    temperature_optimizer_ = &addTensorOptimizer("temperature", {log_temperature_});
    target_entropy_ = o.target_entropy_per_dim * double(a);
  }
  bool needsNextObservations() const override { return true; }
  std::vector<std::string> getLossNames() const override {
    return {"critic_loss", "actor_loss", "temperature", "entropy", "q"};
  }

  // A reparametrized sample and its log-likelihood [B].
  std::pair<torch::Tensor, torch::Tensor> sample(const ObservationBatch& obs) {
    const torch::Tensor out = actor_->forward(obs, {});
    const torch::Tensor mean = out.slice(1, 0, action_dim_);
    const torch::Tensor log_std = out.slice(1, action_dim_).clamp(options_.log_std_min, options_.log_std_max);
    const torch::Tensor noise = torch::randn_like(mean);
    const torch::Tensor u = mean + log_std.exp() * noise;
    const torch::Tensor log_prob = (-0.5 * noise.pow(2) - log_std - 0.5 * std::log(2 * M_PI)).sum(1) -
                                   (2 * (std::log(2.0) - u - torch::softplus(-2 * u))).sum(1);
    return {torch::tanh(u), log_prob};
  }

  std::vector<double> update(const TransitionBatch& b, int64_t iteration) override {
    for (auto& [name, network] : networks_) network->train();
    const torch::Tensor temperature = log_temperature_.exp().detach();
    torch::Tensor target;
    {
      torch::NoGradGuard no_grad;
      const auto [next_action, next_log_prob] = sample(b.next_obs);
      const torch::Tensor q_next = torch::min(critic1_target_->forward(b.next_obs, next_action),
                                              critic2_target_->forward(b.next_obs, next_action)).squeeze(1);
      target = b.rewards + options_.gamma * (1 - b.dones) * (q_next - temperature * next_log_prob);
    }
    const torch::Tensor critic_loss =
        torch::mse_loss(critic1_->forward(b.obs, b.actions).squeeze(1), target) +
        torch::mse_loss(critic2_->forward(b.obs, b.actions).squeeze(1), target);
    step(*critic_optimizer_, critic_loss);

    torch::Tensor action, log_prob, q, actor_loss;
    {
      const FrozenParameters frozen({critic1_.get(), critic2_.get()});
      std::tie(action, log_prob) = sample(b.obs);
      q = torch::min(critic1_->forward(b.obs, action), critic2_->forward(b.obs, action)).squeeze(1);
      actor_loss = (temperature * log_prob - q).mean();
      step(*actor_optimizer_, actor_loss);
    }
    if (options_.tune_temperature) {
      const torch::Tensor by = options_.temperature_gradient_log ? log_temperature_ : log_temperature_.exp();
      step(*temperature_optimizer_, -(by * (log_prob.detach() + target_entropy_)).mean());
    }
    if ((iteration + 1) % options_.target_update_every == 0) {
      softUpdate(*critic1_target_, *critic1_, options_.tau);
      softUpdate(*critic2_target_, *critic2_, options_.tau);
    }
    return {critic_loss.item<double>(), actor_loss.item<double>(), temperature.item<double>(),
            -log_prob.mean().item<double>(), q.mean().item<double>()};
  }

  torch::Tensor act(const ObservationBatch& obs, at::Generator&) override {
    torch::NoGradGuard no_grad;
    actor_->eval();
    return torch::tanh(actor_->forward(obs, {}).slice(1, 0, action_dim_));
  }
  torch::Tensor explore(const ObservationBatch& obs) override {
    torch::NoGradGuard no_grad;
    actor_->eval();
    return sample(obs).first;
  }

 private:
  int64_t action_dim_;
  double target_entropy_;
  std::shared_ptr<Network> actor_, critic1_, critic2_, critic1_target_, critic2_target_;
  torch::Tensor log_temperature_;
  torch::optim::Adam *actor_optimizer_, *critic_optimizer_, *temperature_optimizer_;
};

}  // namespace

std::unique_ptr<Algorithm> makeAlgorithm(const AlgorithmOptions& options, const NetOptions& net,
                                         const ObservationSpec& spec, const torch::Device& device) {
  if (options.batch_size <= 0) throw LearningError("the batch size must be positive");
  if (options.name == "bc") return std::make_unique<BehaviorCloning>(options, net, spec, device);
  if (options.name == "td3bc") return std::make_unique<Td3Bc>(options, net, spec, device);
  if (options.name == "bcq") return std::make_unique<Bcq>(options, net, spec, device);
  if (options.name == "sac") {
    if (options.target_update_every <= 0) throw LearningError("the target update interval must be positive");
    if (options.init_temperature <= 0) throw LearningError("SAC's initial temperature must be positive");
    return std::make_unique<Sac>(options, net, spec, device);
  }
  throw LearningError("unknown algorithm '" + options.name + "' (bc, bcq, td3bc or sac)");
}

}  // namespace manibench::learning
