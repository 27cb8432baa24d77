// The networks of supplement D.2 on libtorch: an MLP for the state mode,
// PointNet, and PointNet + Transformer (one PointNet per mask, one for the
// points in no mask, one for the whole cloud, a state MLP, a task
// embedding, a Transformer encoder without position encoding and attention
// pooling). Every network maps an observation, and optionally an extra
// vector (an action for a Q-network, an action or a latent for BCQ's VAE),
// to an output vector; D.3 feeds the extra vector in beside the robot state.
#pragma once

#include <manibench/learning/robot_frame.hpp>
#include <manibench/learning/spec.hpp>

#include <torch/torch.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace YAML {
class Node;
}

namespace manibench::learning {

// A batch of observations as the networks take them: float32, one device.
struct ObservationBatch {
  torch::Tensor state;  // [B, S]: the task's vector (state mode) or the agent's (pointcloud)
  // pointcloud only: world-frame xyz [B, N, 3], rgb in [0, 1] [B, N, 3],
  // masks [B, N, K] (0 or 1), and valid [B, N] (0 for the zero points
  // that pad a D.1 cloud short of its size).
  torch::Tensor xyz, rgb, seg, valid;

  int64_t size() const { return state.size(0); }
  bool hasPoints() const { return xyz.defined(); }
  // `f` applied to each tensor it holds.
  ObservationBatch map(const std::function<torch::Tensor(const torch::Tensor&)>& f) const;
  // On `device`; `non_blocking`: a copy from pinned memory to CUDA returns
  // before it completes (the device's stream orders it before later work).
  ObservationBatch to(const torch::Device& device, bool non_blocking = false) const;
  // Row i repeated n times in a row (rows i*n .. i*n+n-1): BCQ's action samples.
  ObservationBatch repeatEach(int64_t n) const;
  // Rows `index` (a 1-D int64 tensor).
  ObservationBatch select(const torch::Tensor& index) const;
};

// 1 for real points, 0 for the padding D.1 appends (at the origin, black,
// in no mask: pointcloud.hpp's PointCloudSampling::pad).
torch::Tensor calcValidPoints(const torch::Tensor& xyz, const torch::Tensor& rgb,
                              const torch::Tensor& seg);

enum class NetKind { Mlp, PointNet, PnTransformer };
NetKind parseNetKind(const std::string& name);  // mlp | pointnet | pn_transformer
const char* toString(NetKind kind);

struct NetOptions {
  NetKind kind = NetKind::Mlp;
  // Inputs beyond the current observation, for experts whose phase the
  // state does not show (they switch on step counts): the state vectors of
  // the last `history` observations (1: the current one only; an episode's
  // first observation stands in for those before it), the last
  // `action_history` actions (zeros before the first step), and the step
  // of the episode (step / 100).
  int64_t history = 1;
  int64_t action_history = 0;
  bool step_input = false;
  // The current state's world-frame segments in the robot base's frame,
  // appended last (robot_frame.hpp; off when empty).
  RobotFrameInputs robot_frame;
  // mlp: hidden layers (Table 6's 3 x 256).
  std::vector<int64_t> mlp_hidden{256, 256, 256};
  // pointnet: per-point layers [256, 512], head [512, 256, out] (D.2).
  std::vector<int64_t> point_layers{256, 512};
  std::vector<int64_t> pointnet_head{256};
  // pn_transformer: PointNets and tokens of `width` (D.2: 256), a Transformer
  // of `layers` blocks (ManiSkill-Learn: 6) with `heads` heads of
  // `head_dim` (4 x 32), feed-forward `ff` (1024), dropout; head [width, 128, out].
  int64_t width = 256;
  int64_t layers = 6;
  int64_t heads = 4;
  int64_t head_dim = 32;
  int64_t ff = 1024;
  double dropout = 0.1;
  std::vector<int64_t> transformer_head{128};
  // Whether the transformer's PointNets also see each point's mask
  // channels. ManiSkill-Learn's pop them (each PointNet already sees one
  // mask's points; xyz, rgb and the agent state go in); on: the checkpoints
  // written before this option, which read back with it on.
  bool transformer_masks = false;

  // ManiSkill-Learn's sizes for `algorithm`'s networks: BC's pn_transformer
  // as above; BCQ's and TD3+BC's (its offline-RL configurations) 2 blocks
  // of width 192 and feed-forward 768, which also sets their cost (BCQ
  // runs six such networks, four on 10x repeated clouds).
  static NetOptions makeDefaults(const std::string& algorithm);

  // Whether the state input is more than the current state vector.
  bool hasExtraStateInputs() const {
    return history > 1 || action_history > 0 || step_input || robot_frame.isEnabled();
  }
  void writeYaml(YAML::Node& node) const;
  static NetOptions readYaml(const YAML::Node& node);
};

// The common interface. `extra` is [B, E] or undefined when E = 0.
class Network : public torch::nn::Module {
 public:
  virtual torch::Tensor forward(const ObservationBatch& obs, const torch::Tensor& extra) = 0;
  int64_t getOutputDim() const { return output_dim_; }
  int64_t getExtraDim() const { return extra_dim_; }
  // Per-feature normalization of the state vector ((s - mean) * scale;
  // identity unless set): buffers, so checkpoints carry them.
  void setStateNormalization(const torch::Tensor& mean, const torch::Tensor& scale);

 protected:
  Network(int64_t state_dim, int64_t extra_dim, int64_t output_dim);
  // The normalized state with `extra` appended: what D.3 feeds beside the points.
  torch::Tensor calcStateInput(const ObservationBatch& obs, const torch::Tensor& extra) const;

  int64_t state_dim_, extra_dim_, output_dim_;
  torch::Tensor state_mean_, state_scale_;
};

// The width of the state input: history x the spec's state (or agent)
// vector, action_history x the action, 1 for the step, and the robot-frame
// features.
int64_t calcInputStateDim(const NetOptions& options, const ObservationSpec& spec);

// The state input of one step at a time (what a policy acting in an
// episode feeds its network): [s_t, s_t-1, ..., s_t-history+1, a_t-1, ...,
// a_t-action_history, t / 100, robot_frame(s_t)]. The training batches are built the same
// way (DataChunk, tested equal).
class InputHistory {
 public:
  InputHistory(const NetOptions& options, const ObservationSpec& spec);
  void reset();  // a new episode
  // `state` [1, S] at episode step `step` -> [1, calcInputStateDim()].
  torch::Tensor makeInput(const torch::Tensor& state, int64_t step);
  // The action taken ([A] or [1, A]), clipped to [-1, 1] as the environment does.
  void setAction(const torch::Tensor& action);

 private:
  NetOptions options_;
  std::vector<torch::Tensor> states_;   // newest first
  std::vector<torch::Tensor> actions_;  // newest first
};

std::shared_ptr<Network> makeNetwork(const NetOptions& options, const ObservationSpec& spec,
                                     int64_t extra_dim, int64_t output_dim);

// The tokens a pn_transformer network feeds its Transformer, before the
// task embedding: [B, K + 3, width], the state MLP's, then one per
// PointNet (points in no mask, masks 1..K, the whole cloud). For the tests;
// throws for other networks.
torch::Tensor calcTransformerTokens(Network& network, const ObservationBatch& obs, const torch::Tensor& extra);

// The step feature of NetOptions::step_input (steps as float32, one or many).
inline torch::Tensor calcStepFeature(const torch::Tensor& steps) { return steps / 100.0; }

// Trainable parameters of a module (for docs and logs).
int64_t countParameters(torch::nn::Module& module);

// --- the building blocks, public for the tests ------------------------------------------

// A stack of Linear layers with ReLU between them (and after the last one
// when `activate_last`), Xavier-initialized weights and zero biases as
// ManiSkill-Learn's.
class MlpImpl : public torch::nn::Module {
 public:
  MlpImpl(int64_t input, const std::vector<int64_t>& layers, bool activate_last);
  torch::Tensor forward(torch::Tensor x);
  // The first layer applied to [a, b] without concatenating: a W_a^T +
  // b W_b^T + bias, with a: [..., A] and b broadcast against it.
  torch::Tensor forwardSplitFirst(const torch::Tensor& a, const torch::Tensor& b);
  const std::vector<torch::nn::Linear>& getLinears() const { return linears_; }

 private:
  std::vector<torch::nn::Linear> linears_;
  bool activate_last_;
};
TORCH_MODULE(Mlp);

// One PointNet (D.2): per-point features [xyz - mean, rgb, masks, mean]
// (the mean over the points it sees), concatenated with the state input,
// a shared per-point MLP, and a pooled global feature: max over the first
// half of the channels and mean over the second (ManiSkill-Learn's
// max_mean_mix_aggregation), over the points whose `mask` is 1 (a cloud
// with none pools to zeros).
class PointNetImpl : public torch::nn::Module {
 public:
  PointNetImpl(int64_t mask_count, int64_t state_input, const std::vector<int64_t>& layers,
               bool activate_last);
  // xyz [B,N,3], rgb [B,N,3], seg [B,N,K], state [B,S], mask [B,N] -> [B, layers.back()].
  // Gathers the masked points of each cloud (padded to the largest count in
  // the batch) and applies the first layer's state part once per cloud.
  torch::Tensor forward(const torch::Tensor& xyz, const torch::Tensor& rgb, const torch::Tensor& seg,
                        const torch::Tensor& state, const torch::Tensor& mask);
  // The definition: every point, the state concatenated to each, masked
  // pooling. forward() equals it up to rounding (tested).
  torch::Tensor forwardDefinition(const torch::Tensor& xyz, const torch::Tensor& rgb,
                                  const torch::Tensor& seg, const torch::Tensor& state,
                                  const torch::Tensor& mask);
  int64_t getOutputDim() const { return output_dim_; }

 private:
  Mlp mlp_{nullptr};
  int64_t output_dim_;
};
TORCH_MODULE(PointNet);

// Makes every PointNet of this process run forwardDefinition() (the
// benchmark's like-for-like comparison with a straightforward
// implementation; results equal up to rounding).
void setPointNetDefinitionMode(bool on);

}  // namespace manibench::learning
