#include <manibench/learning/networks.hpp>

#include <yaml-cpp/yaml.h>

#include <atomic>
#include <cmath>
#include <limits>

namespace manibench::learning {

// --- batches ------------------------------------------------------------------------------

ObservationBatch ObservationBatch::map(const std::function<torch::Tensor(const torch::Tensor&)>& f) const {
  ObservationBatch out;
  out.state = f(state);
  if (hasPoints()) {
    out.xyz = f(xyz);
    out.rgb = f(rgb);
    out.seg = f(seg);
    out.valid = f(valid);
  }
  return out;
}

ObservationBatch ObservationBatch::to(const torch::Device& device, bool non_blocking) const {
  return map([&](const torch::Tensor& t) { return t.to(device, non_blocking); });
}

ObservationBatch ObservationBatch::repeatEach(int64_t n) const {
  return map([&](const torch::Tensor& t) { return t.repeat_interleave(n, 0); });
}

ObservationBatch ObservationBatch::select(const torch::Tensor& index) const {
  return map([&](const torch::Tensor& t) { return t.index_select(0, index); });
}

torch::Tensor calcValidPoints(const torch::Tensor& xyz, const torch::Tensor& rgb,
                              const torch::Tensor& seg) {
  torch::Tensor padding = (xyz == 0).all(-1) & (rgb == 0).all(-1);
  if (seg.size(-1) > 0) padding = padding & (seg == 0).all(-1);
  return (~padding).to(torch::kFloat32);
}

// --- options ------------------------------------------------------------------------------

NetKind parseNetKind(const std::string& name) {
  if (name == "mlp") return NetKind::Mlp;
  if (name == "pointnet") return NetKind::PointNet;
  if (name == "pn_transformer") return NetKind::PnTransformer;
  throw LearningError("unknown network '" + name + "' (mlp, pointnet or pn_transformer)");
}

const char* toString(NetKind kind) {
  switch (kind) {
    case NetKind::Mlp: return "mlp";
    case NetKind::PointNet: return "pointnet";
    case NetKind::PnTransformer: return "pn_transformer";
  }
  return "?";
}

void NetOptions::writeYaml(YAML::Node& node) const {
  node["kind"] = toString(kind);
  node["history"] = history;
  node["action_history"] = action_history;
  node["step_input"] = step_input;
  if (robot_frame.isEnabled()) robot_frame.writeYaml(node["robot_frame"]);
  node["mlp_hidden"] = mlp_hidden;
  node["point_layers"] = point_layers;
  node["pointnet_head"] = pointnet_head;
  node["width"] = width;
  node["layers"] = layers;
  node["heads"] = heads;
  node["head_dim"] = head_dim;
  node["ff"] = ff;
  node["dropout"] = dropout;
  node["transformer_head"] = transformer_head;
  node["transformer_masks"] = transformer_masks;
}

NetOptions NetOptions::makeDefaults(const std::string& algorithm) {
  NetOptions o;
  if (algorithm == "bcq" || algorithm == "td3bc") {
    o.width = 192;
    o.layers = 2;
    o.ff = 768;
  }
  return o;
}

NetOptions NetOptions::readYaml(const YAML::Node& node) {
  NetOptions o;
  o.kind = parseNetKind(node["kind"].as<std::string>());
  o.history = node["history"].as<int64_t>(1);
  o.action_history = node["action_history"].as<int64_t>(0);
  o.step_input = node["step_input"].as<bool>(false);
  o.robot_frame = RobotFrameInputs::readYaml(node["robot_frame"]);
  o.mlp_hidden = node["mlp_hidden"].as<std::vector<int64_t>>();
  o.point_layers = node["point_layers"].as<std::vector<int64_t>>();
  o.pointnet_head = node["pointnet_head"].as<std::vector<int64_t>>();
  o.width = node["width"].as<int64_t>();
  o.layers = node["layers"].as<int64_t>();
  o.heads = node["heads"].as<int64_t>();
  o.head_dim = node["head_dim"].as<int64_t>();
  o.ff = node["ff"].as<int64_t>();
  o.dropout = node["dropout"].as<double>();
  o.transformer_head = node["transformer_head"].as<std::vector<int64_t>>();
  o.transformer_masks = node["transformer_masks"].as<bool>(true);  // absent: written before the option
  return o;
}

// --- blocks -------------------------------------------------------------------------------

namespace {

void initLinear(torch::nn::Linear& linear) {
  torch::nn::init::xavier_uniform_(linear->weight);
  torch::nn::init::zeros_(linear->bias);
}

// at::linear, not torch::nn::Linear::forward: libtorch 1.13's C++ module
// (torch/nn/functional/linear.h) runs an input of 3 or more dimensions as a
// matmul and then a separate bias add (and backward as mm plus a reduction),
// where at::linear folds it into one addmm, as python3-torch's nn.Linear
// does. A 2-D input gives the same addmm either way, so the state MLPs are
// unchanged bit for bit. PointNet training at batch 128 on 2 threads (the
// per-point layers take [B, N, F]) went from 0.94x python3-torch to
// 0.98-1.00x, PointNet + Transformer from 1.97x to 2.12x
// (bench/learning_speed.py on a quiet VM; profiled: mm + add where
// python3-torch ran addmm).
torch::Tensor applyLinear(const torch::nn::Linear& linear, const torch::Tensor& x) {
  return torch::linear(x, linear->weight, linear->bias);
}

std::vector<int64_t> append(std::vector<int64_t> layers, int64_t last) {
  layers.push_back(last);
  return layers;
}

}  // namespace

MlpImpl::MlpImpl(int64_t input, const std::vector<int64_t>& layers, bool activate_last)
    : activate_last_(activate_last) {
  int64_t in = input;
  for (std::size_t i = 0; i < layers.size(); ++i) {
    torch::nn::Linear linear(in, layers[i]);
    initLinear(linear);
    linears_.push_back(register_module("linear" + std::to_string(i), linear));
    in = layers[i];
  }
}

namespace {

// Without gradients (acting, target passes) in place on the layer's own
// fresh output: the same values, one activation less to allocate and
// stream through memory (a PointNet layer's is points x width floats per
// cloud; BCQ acts on 100 clouds).
torch::Tensor activate(torch::Tensor x) { return at::GradMode::is_enabled() ? torch::relu(x) : x.relu_(); }

}  // namespace

torch::Tensor MlpImpl::forward(torch::Tensor x) {
  for (std::size_t i = 0; i < linears_.size(); ++i) {
    x = applyLinear(linears_[i], x);
    if (i + 1 < linears_.size() || activate_last_) x = activate(x);
  }
  return x;
}

torch::Tensor MlpImpl::forwardSplitFirst(const torch::Tensor& a, const torch::Tensor& b) {
  const torch::nn::Linear& first = linears_.front();
  const int64_t width_a = a.size(-1);
  const torch::Tensor& w = first->weight;  // [H, A + B]
  torch::Tensor x = torch::linear(a, w.slice(1, 0, width_a), first->bias);
  const torch::Tensor xb = torch::matmul(b, w.slice(1, width_a).t());
  x = at::GradMode::is_enabled() ? x + xb : x.add_(xb);  // (the same sums; in place without gradients)
  if (linears_.size() > 1 || activate_last_) x = activate(x);
  for (std::size_t i = 1; i < linears_.size(); ++i) {
    x = applyLinear(linears_[i], x);
    if (i + 1 < linears_.size() || activate_last_) x = activate(x);
  }
  return x;
}

namespace {

// [xyz - mean, rgb, masks, mean], the mean over the points of `mask`.
torch::Tensor makePointFeatures(const torch::Tensor& xyz, const torch::Tensor& rgb,
                                const torch::Tensor& seg, const torch::Tensor& mask) {
  const torch::Tensor m = mask.unsqueeze(-1);                 // [B, N, 1]
  const torch::Tensor count = m.sum(1, true).clamp_min(1.0);  // [B, 1, 1]
  const torch::Tensor mean = (xyz * m).sum(1, true) / count;  // [B, 1, 3]
  return torch::cat({xyz - mean, rgb, seg, mean.expand_as(xyz)}, -1);
}

// Max over the first half of the channels, mean over the second, over the
// points of `mask` ([B, N]); zeros for a cloud without any.
torch::Tensor poolMaxMean(const torch::Tensor& features, const torch::Tensor& mask) {
  const int64_t channels = features.size(-1), half = channels / 2;
  const torch::Tensor m = mask.unsqueeze(-1);
  const torch::Tensor count = mask.sum(1, true);  // [B, 1]
  torch::Tensor max = features.slice(-1, 0, half)
                          .masked_fill(m == 0, -std::numeric_limits<float>::infinity())
                          .amax(1);
  max = torch::where(count > 0, max, torch::zeros_like(max));
  const torch::Tensor mean = (features.slice(-1, half) * m).sum(1) / count.clamp_min(1.0);
  return torch::cat({max, mean}, -1);
}

}  // namespace

namespace {
std::atomic<bool> g_pointnet_definition{false};
}  // namespace

void setPointNetDefinitionMode(bool on) { g_pointnet_definition = on; }

PointNetImpl::PointNetImpl(int64_t mask_count, int64_t state_input,
                           const std::vector<int64_t>& layers, bool activate_last)
    : output_dim_(layers.back()) {
  const int64_t point_features = 3 + 3 + mask_count + 3;
  mlp_ = register_module("mlp", Mlp(point_features + state_input, layers, activate_last));
}

torch::Tensor PointNetImpl::forward(const torch::Tensor& xyz, const torch::Tensor& rgb,
                                    const torch::Tensor& seg, const torch::Tensor& state,
                                    const torch::Tensor& mask) {
  if (g_pointnet_definition) return forwardDefinition(xyz, rgb, seg, state, mask);
  const int64_t batch = xyz.size(0), points = xyz.size(1), masks = seg.size(2);
  // The gather's size is data (the fullest cloud's count), which a CUDA
  // device would have to hand back to the host on every call (about 30
  // syncs per BCQ or TD3+BC update): off the CPU every point stays, and the
  // masked pooling below ignores the others, as the definition does. On
  // the CPU the count costs nothing and the gather saves the per-point
  // layers of the points outside the mask.
  const int64_t most =
      xyz.is_cpu() ? std::max<int64_t>(1, int64_t(mask.sum(1).max().item<float>())) : points;
  torch::Tensor gxyz = xyz, grgb = rgb, gseg = seg, gmask = mask;
  if (most < points) {
    // Members first, in their order; then as many rows as the fullest cloud.
    const torch::Tensor order = std::get<1>(mask.sort(/*stable=*/true, /*dim=*/1, /*descending=*/true));
    const torch::Tensor index = order.slice(1, 0, most);  // [B, C]
    const torch::Tensor index3 = index.unsqueeze(-1);
    gmask = mask.gather(1, index);
    gxyz = xyz.gather(1, index3.expand({batch, most, 3}));
    grgb = rgb.gather(1, index3.expand({batch, most, 3}));
    gseg = seg.gather(1, index3.expand({batch, most, masks}));
  }
  const torch::Tensor features = makePointFeatures(gxyz, grgb, gseg, gmask);
  const torch::Tensor h = mlp_->forwardSplitFirst(features, state.unsqueeze(1));
  return poolMaxMean(h, gmask);
}

torch::Tensor PointNetImpl::forwardDefinition(const torch::Tensor& xyz, const torch::Tensor& rgb,
                                              const torch::Tensor& seg, const torch::Tensor& state,
                                              const torch::Tensor& mask) {
  const torch::Tensor features = makePointFeatures(xyz, rgb, seg, mask);
  const torch::Tensor per_point =
      torch::cat({features, state.unsqueeze(1).expand({xyz.size(0), xyz.size(1), state.size(1)})}, -1);
  return poolMaxMean(mlp_->forward(per_point), mask);
}

// --- networks -----------------------------------------------------------------------------

Network::Network(int64_t state_dim, int64_t extra_dim, int64_t output_dim)
    : state_dim_(state_dim), extra_dim_(extra_dim), output_dim_(output_dim) {
  state_mean_ = register_buffer("state_mean", torch::zeros({state_dim}));
  state_scale_ = register_buffer("state_scale", torch::ones({state_dim}));
}

void Network::setStateNormalization(const torch::Tensor& mean, const torch::Tensor& scale) {
  torch::NoGradGuard no_grad;
  state_mean_.copy_(mean);
  state_scale_.copy_(scale);
}

torch::Tensor Network::calcStateInput(const ObservationBatch& obs, const torch::Tensor& extra) const {
  if (obs.state.size(1) != state_dim_)
    throw LearningError("the network takes a state of " + std::to_string(state_dim_) +
                        " values, the observation has " + std::to_string(obs.state.size(1)));
  torch::Tensor s = (obs.state - state_mean_) * state_scale_;
  if (extra_dim_ == 0) return s;
  if (!extra.defined() || extra.size(1) != extra_dim_)
    throw LearningError("the network takes an extra input of " + std::to_string(extra_dim_) +
                        " values");
  return torch::cat({s, extra}, 1);
}

namespace {

class MlpNetwork : public Network {
 public:
  MlpNetwork(const NetOptions& o, const ObservationSpec& spec, int64_t extra, int64_t out)
      : Network(calcInputStateDim(o, spec), extra, out) {
    mlp_ = register_module("mlp", Mlp(state_dim_ + extra, append(o.mlp_hidden, out), false));
  }
  torch::Tensor forward(const ObservationBatch& obs, const torch::Tensor& extra) override {
    return mlp_->forward(calcStateInput(obs, extra));
  }

 private:
  Mlp mlp_{nullptr};
};

class PointNetNetwork : public Network {
 public:
  PointNetNetwork(const NetOptions& o, const ObservationSpec& spec, int64_t extra, int64_t out)
      : Network(calcInputStateDim(o, spec), extra, out) {
    pointnet_ = register_module(
        "pointnet", PointNet(spec.mask_count, state_dim_ + extra, o.point_layers, true));
    head_ = register_module("head", Mlp(pointnet_->getOutputDim(), append(o.pointnet_head, out), false));
  }
  torch::Tensor forward(const ObservationBatch& obs, const torch::Tensor& extra) override {
    if (!obs.hasPoints()) throw LearningError("the pointnet network needs point clouds");
    const torch::Tensor s = calcStateInput(obs, extra);
    return head_->forward(pointnet_->forward(obs.xyz, obs.rgb, obs.seg, s, obs.valid));
  }

 private:
  PointNet pointnet_{nullptr};
  Mlp head_{nullptr};
};

// Multi-head self-attention over tokens, with a [B, T, T] mask of who may
// attend to whom (ManiSkill-Learn's MultiHeadSelfAttention: heads of
// `head_dim`, not width / heads).
class SelfAttentionImpl : public torch::nn::Module {
 public:
  SelfAttentionImpl(int64_t width, int64_t heads, int64_t head_dim, double dropout)
      : heads_(heads), head_dim_(head_dim) {
    for (auto* l : {&q_, &k_, &v_}) {
      *l = torch::nn::Linear(width, heads * head_dim);
      initLinear(*l);
    }
    out_ = torch::nn::Linear(heads * head_dim, width);
    initLinear(out_);
    register_module("q", q_);
    register_module("k", k_);
    register_module("v", v_);
    register_module("out", out_);
    dropout_ = register_module("dropout", torch::nn::Dropout(dropout));
  }
  torch::Tensor forward(const torch::Tensor& x, const torch::Tensor& mask) {
    const int64_t b = x.size(0), t = x.size(1);
    auto split = [&](const torch::Tensor& y) { return y.view({b, t, heads_, head_dim_}).transpose(1, 2); };
    const torch::Tensor q = split(applyLinear(q_, x)), k = split(applyLinear(k_, x)), v = split(applyLinear(v_, x));
    torch::Tensor scores = torch::matmul(q, k.transpose(-2, -1)) / std::sqrt(double(head_dim_));
    scores = scores.masked_fill(mask.unsqueeze(1) == 0, -std::numeric_limits<float>::infinity());
    const torch::Tensor attention = dropout_->forward(torch::softmax(scores, -1));
    const torch::Tensor o = torch::matmul(attention, v).transpose(1, 2).reshape({b, t, heads_ * head_dim_});
    return applyLinear(out_, o);
  }

 private:
  int64_t heads_, head_dim_;
  torch::nn::Linear q_{nullptr}, k_{nullptr}, v_{nullptr}, out_{nullptr};
  torch::nn::Dropout dropout_{nullptr};
};
TORCH_MODULE(SelfAttention);

// Post-norm block: x = LN(x + attention(x)); x = LN(x + dropout(MLP(x))).
class TransformerBlockImpl : public torch::nn::Module {
 public:
  TransformerBlockImpl(const NetOptions& o) {
    attention_ = register_module("attention", SelfAttention(o.width, o.heads, o.head_dim, o.dropout));
    mlp_ = register_module("mlp", Mlp(o.width, std::vector<int64_t>{o.ff, o.width}, false));
    norm1_ = register_module("norm1", torch::nn::LayerNorm(torch::nn::LayerNormOptions({o.width})));
    norm2_ = register_module("norm2", torch::nn::LayerNorm(torch::nn::LayerNormOptions({o.width})));
    dropout_ = register_module("dropout", torch::nn::Dropout(o.dropout));
  }
  torch::Tensor forward(torch::Tensor x, const torch::Tensor& mask) {
    x = norm1_->forward(x + attention_->forward(x, mask));
    return norm2_->forward(x + dropout_->forward(mlp_->forward(x)));
  }

 private:
  SelfAttention attention_{nullptr};
  Mlp mlp_{nullptr};
  torch::nn::LayerNorm norm1_{nullptr}, norm2_{nullptr};
  torch::nn::Dropout dropout_{nullptr};
};
TORCH_MODULE(TransformerBlock);

// A learned query per head attends over the tokens a [B, T] mask allows.
class AttentionPoolingImpl : public torch::nn::Module {
 public:
  AttentionPoolingImpl(int64_t width, int64_t heads, int64_t head_dim) : heads_(heads), head_dim_(head_dim) {
    query_ = register_parameter("query", torch::empty({heads, head_dim}));
    torch::nn::init::xavier_normal_(query_);
    k_ = torch::nn::Linear(width, heads * head_dim);
    v_ = torch::nn::Linear(width, heads * head_dim);
    out_ = torch::nn::Linear(heads * head_dim, width);
    for (auto* l : {&k_, &v_, &out_}) initLinear(*l);
    register_module("k", k_);
    register_module("v", v_);
    register_module("out", out_);
  }
  torch::Tensor forward(const torch::Tensor& x, const torch::Tensor& mask) {
    const int64_t b = x.size(0), t = x.size(1);
    const torch::Tensor k = applyLinear(k_, x).view({b, t, heads_, head_dim_});
    const torch::Tensor v = applyLinear(v_, x).view({b, t, heads_, head_dim_});
    torch::Tensor scores = (k * query_).sum(-1) / std::sqrt(double(head_dim_));  // [B, T, H]
    scores = scores.masked_fill(mask.unsqueeze(-1) == 0, -std::numeric_limits<float>::infinity());
    const torch::Tensor weights = torch::softmax(scores, 1).unsqueeze(-1);  // [B, T, H, 1]
    return applyLinear(out_, (weights * v).sum(1).reshape({b, heads_ * head_dim_}));
  }

 private:
  int64_t heads_, head_dim_;
  torch::Tensor query_;
  torch::nn::Linear k_{nullptr}, v_{nullptr}, out_{nullptr};
};
TORCH_MODULE(AttentionPooling);

// D.2's PointNet + Transformer. Tokens: the task embedding, the state
// MLP's, then one per PointNet: points in no mask, each mask, the whole
// cloud. A token whose points are absent neither attends nor is attended
// (the task embedding attends to all, as ManiSkill-Learn's).
class PnTransformerNetwork : public Network {
 public:
  PnTransformerNetwork(const NetOptions& o, const ObservationSpec& spec, int64_t extra, int64_t out)
      : Network(calcInputStateDim(o, spec), extra, out), mask_count_(spec.mask_count),
        pointnet_masks_(o.transformer_masks ? spec.mask_count : 0) {
    const int64_t state_input = state_dim_ + extra;
    for (int64_t i = 0; i < mask_count_ + 2; ++i) {
      pointnets_.push_back(register_module("pointnet" + std::to_string(i),
                                           PointNet(pointnet_masks_, state_input, std::vector<int64_t>{o.width, o.width}, false)));
      globals_.push_back(register_module("global" + std::to_string(i),
                                         Mlp(o.width, std::vector<int64_t>{o.width, o.width}, false)));
    }
    state_mlp_ = register_module("state_mlp", Mlp(state_input, std::vector<int64_t>{o.width, o.width}, false));
    task_embedding_ = register_parameter("task_embedding", torch::empty({1, 1, o.width}));
    torch::nn::init::xavier_normal_(task_embedding_);
    for (int64_t i = 0; i < o.layers; ++i)
      blocks_.push_back(register_module("block" + std::to_string(i), TransformerBlock(o)));
    pooling_ = register_module("pooling", AttentionPooling(o.width, o.heads, o.head_dim));
    head_ = register_module("head", Mlp(o.width, append(o.transformer_head, out), false));
  }

  // The [B, N] point masks of the PointNets, in token order.
  std::vector<torch::Tensor> calcPointMasks(const ObservationBatch& obs) const {
    std::vector<torch::Tensor> masks;
    const torch::Tensor in_some = mask_count_ > 0 ? (obs.seg.sum(-1) > 0.5).to(torch::kFloat32)
                                                  : torch::zeros_like(obs.valid);
    masks.push_back(obs.valid * (1 - in_some));
    for (int64_t j = 0; j < mask_count_; ++j) masks.push_back(obs.seg.select(-1, j) * obs.valid);
    masks.push_back(obs.valid);
    return masks;
  }

  // The tokens after the task embedding, [B, T - 1, W], and whether each
  // has points ([B, T - 1]; the state's always does).
  std::pair<torch::Tensor, torch::Tensor> calcTokens(const ObservationBatch& obs, const torch::Tensor& extra) {
    if (!obs.hasPoints()) throw LearningError("the pn_transformer network needs point clouds");
    const torch::Tensor s = calcStateInput(obs, extra);
    const std::vector<torch::Tensor> masks = calcPointMasks(obs);
    std::vector<torch::Tensor> tokens{state_mlp_->forward(s)};
    std::vector<torch::Tensor> present{torch::ones({obs.size()}, s.options())};
    const torch::Tensor seg = obs.seg.slice(-1, 0, pointnet_masks_);
    for (std::size_t i = 0; i < masks.size(); ++i) {
      tokens.push_back(globals_[i]->forward(pointnets_[i]->forward(obs.xyz, obs.rgb, seg, s, masks[i])));
      present.push_back((masks[i].sum(1) > 0).to(torch::kFloat32));
    }
    return {torch::stack(tokens, 1), torch::stack(present, 1)};
  }

  torch::Tensor forward(const ObservationBatch& obs, const torch::Tensor& extra) override {
    const int64_t b = obs.size();
    const auto [tokens, p] = calcTokens(obs, extra);  // [B, T - 1, W], [B, T - 1]
    torch::Tensor x = torch::cat({task_embedding_.expand({b, 1, task_embedding_.size(2)}), tokens}, 1);
    torch::Tensor mask = p.unsqueeze(2) * p.unsqueeze(1);         // [B, T - 1, T - 1]
    mask = torch::cat({torch::ones({b, 1, mask.size(2)}, mask.options()), mask}, 1);
    mask = torch::cat({torch::ones({b, mask.size(1), 1}, mask.options()), mask}, 2);  // [B, T, T]
    for (auto& block : blocks_) x = block->forward(x, mask);
    // Pool over what the whole cloud's token attends to (ManiSkill-Learn).
    return head_->forward(pooling_->forward(x, mask.select(1, mask.size(1) - 1)));
  }

 private:
  int64_t mask_count_;
  int64_t pointnet_masks_;  // the mask channels each PointNet sees (NetOptions::transformer_masks)
  std::vector<PointNet> pointnets_;
  std::vector<Mlp> globals_;
  Mlp state_mlp_{nullptr};
  torch::Tensor task_embedding_;
  std::vector<TransformerBlock> blocks_;
  AttentionPooling pooling_{nullptr};
  Mlp head_{nullptr};
};

}  // namespace

int64_t calcInputStateDim(const NetOptions& options, const ObservationSpec& spec) {
  return options.history * int64_t(spec.state_dim) + options.action_history * int64_t(spec.action_dim) +
         (options.step_input ? 1 : 0) + options.robot_frame.calcDim();
}

InputHistory::InputHistory(const NetOptions& options, const ObservationSpec& spec) : options_(options) {
  actions_.assign(std::size_t(options.action_history), torch::zeros({1, int64_t(spec.action_dim)}));
}

void InputHistory::reset() {
  states_.clear();
  for (torch::Tensor& a : actions_) a.zero_();
}

torch::Tensor InputHistory::makeInput(const torch::Tensor& state, int64_t step) {
  if (!options_.hasExtraStateInputs()) return state;
  if (states_.empty()) {
    states_.assign(std::size_t(options_.history), state);
  } else {
    states_.pop_back();
    states_.insert(states_.begin(), state);
  }
  std::vector<torch::Tensor> parts = states_;
  parts.insert(parts.end(), actions_.begin(), actions_.end());
  if (options_.step_input) parts.push_back(calcStepFeature(torch::full({1, 1}, float(step))));
  if (options_.robot_frame.isEnabled()) parts.push_back(calcRobotFrameFeatures(options_.robot_frame, state));
  return torch::cat(parts, 1);
}

void InputHistory::setAction(const torch::Tensor& action) {
  if (actions_.empty()) return;
  actions_.pop_back();
  actions_.insert(actions_.begin(), action.reshape({1, -1}).clamp(-1, 1));
}

std::shared_ptr<Network> makeNetwork(const NetOptions& options, const ObservationSpec& spec,
                                     int64_t extra_dim, int64_t output_dim) {
  if (options.history < 1 || options.action_history < 0)
    throw LearningError("the history must be at least 1 observation and 0 actions");
  if (options.kind != NetKind::Mlp && !spec.isPointCloud())
    throw LearningError(std::string("the ") + toString(options.kind) +
                        " network needs pointcloud observations, but the data are " + spec.mode +
                        " (" + spec.describe() + "); convert them with `manibench demos convert " +
                        "FILE --obs pointcloud`, or use --net mlp");
  if (options.kind == NetKind::Mlp && spec.mode != "state")
    throw LearningError("the mlp network takes the state mode, but the data are " + spec.mode +
                        " (" + spec.describe() + "); use --net pointnet or pn_transformer");
  switch (options.kind) {
    case NetKind::Mlp: return std::make_shared<MlpNetwork>(options, spec, extra_dim, output_dim);
    case NetKind::PointNet: return std::make_shared<PointNetNetwork>(options, spec, extra_dim, output_dim);
    case NetKind::PnTransformer:
      return std::make_shared<PnTransformerNetwork>(options, spec, extra_dim, output_dim);
  }
  throw LearningError("unknown network kind");
}

torch::Tensor calcTransformerTokens(Network& network, const ObservationBatch& obs, const torch::Tensor& extra) {
  auto* transformer = dynamic_cast<PnTransformerNetwork*>(&network);
  if (transformer == nullptr) throw LearningError("not a pn_transformer network");
  return transformer->calcTokens(obs, extra).first;
}

int64_t countParameters(torch::nn::Module& module) {
  int64_t n = 0;
  for (const torch::Tensor& p : module.parameters()) n += p.numel();
  return n;
}

}  // namespace manibench::learning
