// The learning-from-demonstrations algorithms of supplement D.3: Behavior
// Cloning (MSE on the demonstrated actions), BCQ (Fujimoto et al. 2019:
// a VAE of the demonstrated actions, twin Q-networks, the best of n
// sampled actions; Table 7) and TD3+BC (Fujimoto & Gu 2021: TD3 with a
// BC term, lambda = alpha / mean |Q|; Table 8); and SAC (Haarnoja et al.
// 2018, with automatic entropy tuning; Table 6), the online agent of
// supplement C.2 that sac_trainer.hpp feeds from environment workers. Each
// owns its networks and optimizers, takes one gradient step per update()
// and acts on a batch of observations.
#pragma once

#include <manibench/learning/networks.hpp>

#include <torch/torch.h>

#include <memory>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

namespace manibench::learning {

struct AlgorithmOptions {
  std::string name = "bc";  // bc | bcq | td3bc | sac
  int64_t batch_size = 128;
  double lr = 3e-4;
  double weight_decay = 0;
  // BC's action is tanh(network output), as ManiSkill-Learn's
  // DeterministicHead (and TD3+BC's actor, BCQ's decoder, SAC's squashed
  // Gaussian). Off: the output as it is (the checkpoints written before
  // this option, which read back with it off).
  bool bc_tanh = true;
  // Offline RL (BCQ, TD3+BC).
  double gamma = 0.95;
  double tau = 0.005;
  // BCQ (Table 7): perturbation limit Phi (0: the VAE's samples as they
  // are, no perturbation network), samples at training and evaluation,
  // the clipped double-Q weight lambda, the VAE's KL weight.
  double phi = 0.0;
  int64_t train_samples = 10;
  int64_t eval_samples = 100;
  double lambda = 0.75;
  double kl_weight = 0.5;
  // TD3+BC (Table 8): alpha (0 = BC), target policy noise and its clip,
  // actor and target updates every `policy_delay` critic updates.
  double alpha = 0.02;
  double action_noise = 0.2;
  double noise_clip = 0.5;
  int64_t policy_delay = 2;
  // SAC (Table 6; the table is silent on the entropy terms, these are
  // ManiSkill-Learn's): the initial temperature (ManiSkill-Learn's SAC
  // starts its tuned temperature at log alpha = 0, alpha = 1, whatever
  // its configuration's alpha says), whether it is tuned towards the target
  // entropy (per action dimension: -1 gives the usual -|A|) by a loss
  // alpha * -(log pi + target) differentiated with respect to alpha, as
  // ManiSkill-Learn's (`temperature_gradient_log`: with respect to log
  // alpha instead, as Haarnoja et al.'s code and manibench before this
  // option), the log std's clamp, and the target networks' update
  // interval in gradient steps (Table 6: every step).
  double init_temperature = 1.0;
  bool temperature_gradient_log = false;
  bool tune_temperature = true;
  double target_entropy_per_dim = -1.0;
  double log_std_min = -20, log_std_max = 2;
  int64_t target_update_every = 1;

  // The tables' values (and ManiSkill-Learn's where the tables are
  // silent) for `name` on observations of `mode` (BC's learning rate and the
  // weight decay are ManiSkill-Learn's for the mode); throws LearningError
  // for an unknown name.
  static AlgorithmOptions makeDefaults(const std::string& name, const std::string& mode = "state");
  void writeYaml(YAML::Node& node) const;
  static AlgorithmOptions readYaml(const YAML::Node& node);
};

// One minibatch of transitions. next_obs only for the offline RL
// algorithms; dones are 1 where the episode ended by success.
struct TransitionBatch {
  ObservationBatch obs, next_obs;
  torch::Tensor actions;  // [B, A], clipped to [-1, 1]
  torch::Tensor rewards;  // [B]
  torch::Tensor dones;    // [B]
  // `f` applied to each tensor it holds (ObservationBatch::map).
  TransitionBatch map(const std::function<torch::Tensor(const torch::Tensor&)>& f) const;
  TransitionBatch to(const torch::Device& device, bool non_blocking = false) const;
};

class Algorithm {
 public:
  virtual ~Algorithm() = default;
  Algorithm(const Algorithm&) = delete;
  Algorithm& operator=(const Algorithm&) = delete;

  const AlgorithmOptions& getOptions() const { return options_; }
  virtual bool needsNextObservations() const = 0;
  virtual std::vector<std::string> getLossNames() const = 0;
  // Gradient step number `iteration` (0, 1, ...; TD3+BC's delayed actor
  // updates count them), in training mode; the losses in getLossNames()'s order.
  virtual std::vector<double> update(const TransitionBatch& batch, int64_t iteration) = 0;
  // Actions [B, A] in evaluation mode, without gradients; `generator`
  // draws BCQ's samples (the others are deterministic; SAC's is the tanh
  // of its Gaussian's mean).
  virtual torch::Tensor act(const ObservationBatch& obs, at::Generator& generator) = 0;
  // Exploration actions [B, A] in [-1, 1], without gradients, drawn from
  // libtorch's default generator: the online algorithms' (SAC's squashed
  // Gaussian); the offline ones throw.
  virtual torch::Tensor explore(const ObservationBatch& obs);

  // The networks and optimizers by name ("actor", "critic1", ...).
  const std::vector<std::pair<std::string, std::shared_ptr<Network>>>& getNetworks() const {
    return networks_;
  }
  // Sets the state normalization of every network.
  void setStateNormalization(const torch::Tensor& mean, const torch::Tensor& scale);
  // Writes / reads the networks (and optimizers, and the lone parameters
  // such as SAC's temperature) under "net.NAME" ("optim.NAME", "param.NAME").
  void save(torch::serialize::OutputArchive& archive, bool with_optimizers) const;
  void load(torch::serialize::InputArchive& archive, bool with_optimizers);

 protected:
  explicit Algorithm(const AlgorithmOptions& options) : options_(options) {}
  std::shared_ptr<Network> addNetwork(const std::string& name, std::shared_ptr<Network> network,
                                      const torch::Device& device);
  // An Adam optimizer over `names`' parameters.
  torch::optim::Adam& addOptimizer(const std::string& name, const std::vector<std::string>& networks);
  // An Adam optimizer over tensors that belong to no network.
  torch::optim::Adam& addTensorOptimizer(const std::string& name, std::vector<torch::Tensor> parameters);
  // critic1, critic2 (obs, a) -> Q and their targets (copies), in that order.
  std::tuple<std::shared_ptr<Network>, std::shared_ptr<Network>, std::shared_ptr<Network>, std::shared_ptr<Network>>
  addTwinCritics(const NetOptions& net, const ObservationSpec& spec, const torch::Device& device);
  // A trainable tensor outside the networks, saved with them.
  torch::Tensor addParameter(const std::string& name, torch::Tensor value);
  std::shared_ptr<Network> getNetwork(const std::string& name) const;

  AlgorithmOptions options_;
  std::vector<std::pair<std::string, std::shared_ptr<Network>>> networks_;
  std::vector<std::pair<std::string, std::unique_ptr<torch::optim::Adam>>> optimizers_;
  std::vector<std::pair<std::string, torch::Tensor>> parameters_;
};

std::unique_ptr<Algorithm> makeAlgorithm(const AlgorithmOptions& options, const NetOptions& net,
                                         const ObservationSpec& spec, const torch::Device& device);

// target <- (1 - tau) target + tau source, parameter by parameter.
void softUpdate(torch::nn::Module& target, const torch::nn::Module& source, double tau);

// Whether the actor's gradient step freezes the critics it differentiates
// through (on by default: the critics' parameter gradients were computed
// and thrown away). Off is the reference the benchmark and the tests compare
// against; the weights are the same bit for bit either way.
void setActorStepFreezesCritics(bool on);

}  // namespace manibench::learning
