// The networks, algorithms and checkpoints of the learning module on
// synthetic batches (no files, no environment): shapes, PointNet's
// invariances, PointNet + Transformer's routing of masked points, the fast
// PointNet against its definition, and checkpoints that restore exactly.
#include <manibench/learning/algorithms.hpp>
#include <manibench/learning/checkpoint.hpp>
#include <manibench/learning/compute.hpp>
#include <manibench/learning/inference.hpp>
#include <manibench/learning/networks.hpp>
#include <manibench/learning/robot_frame.hpp>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

namespace manibench::learning {
namespace {

ObservationSpec makeStateSpec() {
  ObservationSpec s;
  s.task = "Synthetic-v0";
  s.mode = "state";
  s.state_dim = 10;
  s.state_segments = {{"a", 0, 4}, {"b", 4, 6}};
  s.action_dim = 3;
  s.action_segments = {{"arm", 0, 3}};
  return s;
}

ObservationSpec makeCloudSpec() {
  ObservationSpec s = makeStateSpec();
  s.mode = "pointcloud";
  s.state_dim = 6;
  s.state_segments = {{"agent", 0, 6}};
  s.point_count = 64;
  s.mask_count = 3;
  return s;
}

// Clouds whose points are each in at most one mask: mask j for points
// 8j..8j+7, no mask for the rest; the last 4 points pad the cloud.
ObservationBatch makeCloudBatch(int64_t batch, const ObservationSpec& spec, uint64_t seed = 1) {
  torch::manual_seed(seed);
  ObservationBatch b;
  const int64_t n = spec.point_count, k = spec.mask_count;
  b.state = torch::randn({batch, int64_t(spec.state_dim)});
  b.xyz = torch::rand({batch, n, 3}) + 0.1;
  b.rgb = torch::rand({batch, n, 3});
  torch::Tensor seg = torch::zeros({batch, n, k});
  for (int64_t j = 0; j < k; ++j) seg.slice(1, 8 * j, 8 * j + 8).select(2, j).fill_(1);
  b.xyz.slice(1, n - 4).zero_();
  b.rgb.slice(1, n - 4).zero_();
  b.seg = seg;
  b.valid = calcValidPoints(b.xyz, b.rgb, b.seg);
  return b;
}

ObservationBatch makeStateBatch(int64_t batch, const ObservationSpec& spec) {
  ObservationBatch b;
  b.state = torch::randn({batch, int64_t(spec.state_dim)});
  return b;
}

NetOptions makeNet(NetKind kind) {
  NetOptions o;
  o.kind = kind;
  o.layers = 2;  // small Transformers keep the tests quick
  return o;
}

TEST(LearningNetworks, OutputShapesPerNetworkAndMode) {
  torch::manual_seed(0);
  const ObservationSpec state = makeStateSpec(), cloud = makeCloudSpec();
  const auto mlp = makeNetwork(makeNet(NetKind::Mlp), state, 0, 3);
  EXPECT_EQ(mlp->forward(makeStateBatch(5, state), {}).sizes(), (std::vector<int64_t>{5, 3}));
  const auto q = makeNetwork(makeNet(NetKind::Mlp), state, 3, 1);
  EXPECT_EQ(q->forward(makeStateBatch(5, state), torch::zeros({5, 3})).sizes(), (std::vector<int64_t>{5, 1}));
  for (NetKind kind : {NetKind::PointNet, NetKind::PnTransformer}) {
    SCOPED_TRACE(toString(kind));
    const auto actor = makeNetwork(makeNet(kind), cloud, 0, 3);
    EXPECT_EQ(actor->forward(makeCloudBatch(4, cloud), {}).sizes(), (std::vector<int64_t>{4, 3}));
    const auto critic = makeNetwork(makeNet(kind), cloud, 3, 1);
    EXPECT_EQ(critic->forward(makeCloudBatch(4, cloud), torch::zeros({4, 3})).sizes(),
              (std::vector<int64_t>{4, 1}));
  }
}

TEST(LearningNetworks, NetworksRefuseTheWrongMode) {
  try {
    makeNetwork(makeNet(NetKind::PointNet), makeStateSpec(), 0, 3);
    FAIL() << "a pointnet on state observations was made";
  } catch (const LearningError& e) {
    EXPECT_NE(std::string(e.what()).find("needs pointcloud observations"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("demos convert"), std::string::npos) << e.what();
  }
  EXPECT_THROW(makeNetwork(makeNet(NetKind::Mlp), makeCloudSpec(), 0, 3), LearningError);
}

TEST(LearningNetworks, PaddingPointsAreInvalid) {
  const ObservationBatch b = makeCloudBatch(2, makeCloudSpec());
  EXPECT_EQ(b.valid.sum().item<float>(), 2 * 60);
  EXPECT_EQ(b.valid[0][63].item<float>(), 0);
  EXPECT_EQ(b.valid[0][0].item<float>(), 1);
}

TEST(LearningNetworks, PointNetsAreInvariantToTheOrderOfPoints) {
  torch::manual_seed(0);
  const ObservationSpec spec = makeCloudSpec();
  for (NetKind kind : {NetKind::PointNet, NetKind::PnTransformer}) {
    SCOPED_TRACE(toString(kind));
    const auto net = makeNetwork(makeNet(kind), spec, 0, 3);
    net->eval();
    const ObservationBatch b = makeCloudBatch(3, spec);
    const torch::Tensor order = torch::randperm(spec.point_count);
    ObservationBatch shuffled = b;
    shuffled.xyz = b.xyz.index_select(1, order);
    shuffled.rgb = b.rgb.index_select(1, order);
    shuffled.seg = b.seg.index_select(1, order);
    shuffled.valid = b.valid.index_select(1, order);
    const torch::Tensor a = net->forward(b, {}), c = net->forward(shuffled, {});
    EXPECT_TRUE(torch::allclose(a, c, 1e-5, 1e-5)) << a << c;
    EXPECT_FALSE(torch::equal(a, net->forward(makeCloudBatch(3, spec, 7), {})));
  }
}

TEST(LearningNetworks, FastPointNetEqualsItsDefinition) {
  torch::manual_seed(3);
  const ObservationSpec spec = makeCloudSpec();
  PointNet pointnet(3, 6, std::vector<int64_t>{32, 16}, false);
  const ObservationBatch b = makeCloudBatch(4, spec);
  // Mask 1 of each cloud, but none in cloud 2 (an empty sub-cloud pools to zeros).
  torch::Tensor mask = b.seg.select(2, 1) * b.valid;
  mask[2].zero_();
  const torch::Tensor fast = pointnet->forward(b.xyz, b.rgb, b.seg, b.state, mask);
  const torch::Tensor definition = pointnet->forwardDefinition(b.xyz, b.rgb, b.seg, b.state, mask);
  EXPECT_TRUE(torch::allclose(fast, definition, 1e-5, 1e-5)) << fast - definition;
  EXPECT_EQ(fast[2].abs().sum().item<float>(), 0);
  EXPECT_GT(fast[0].abs().sum().item<float>(), 0);
  // And with every valid point (no gathering).
  EXPECT_TRUE(torch::allclose(pointnet->forward(b.xyz, b.rgb, b.seg, b.state, b.valid),
                              pointnet->forwardDefinition(b.xyz, b.rgb, b.seg, b.state, b.valid), 1e-5, 1e-5));
  // On CUDA, the fixed-size path without a host sync: the same pooled features.
  if (!torch::cuda::is_available()) return;
  pointnet->to(torch::kCUDA);
  const ObservationBatch c = b.to(torch::kCUDA);
  EXPECT_TRUE(torch::allclose(pointnet->forward(c.xyz, c.rgb, c.seg, c.state, mask.to(torch::kCUDA)).cpu(), definition,
                              1e-4, 1e-4));
}

// Which of the K + 3 tokens change when point `point` of cloud 0 changes colour.
std::vector<int64_t> changedTokens(Network& net, const ObservationBatch& b, int64_t point) {
  const torch::Tensor before = calcTransformerTokens(net, b, {});
  ObservationBatch changed = b;
  changed.rgb = b.rgb.clone();
  changed.rgb[0][point] += 0.5;
  const torch::Tensor after = calcTransformerTokens(net, changed, {});
  std::vector<int64_t> out;
  for (int64_t t = 0; t < before.size(1); ++t)
    if (!torch::equal(before[0][t], after[0][t])) out.push_back(t);
  EXPECT_TRUE(torch::equal(before[1], after[1])) << "another cloud changed";
  return out;
}

TEST(LearningNetworks, APointInMaskJReachesOnlyPointNetJAndTheWholeCloud) {
  torch::manual_seed(0);
  const ObservationSpec spec = makeCloudSpec();
  const auto net = makeNetwork(makeNet(NetKind::PnTransformer), spec, 0, 3);
  net->eval();
  const ObservationBatch b = makeCloudBatch(2, spec);
  // Tokens: 0 state, 1 points in no mask, 2 + j mask j, 2 + K the whole cloud.
  for (int64_t j = 0; j < 3; ++j) {
    SCOPED_TRACE("mask " + std::to_string(j));
    EXPECT_EQ(changedTokens(*net, b, 8 * j + 3), (std::vector<int64_t>{2 + j, 5}));
  }
  EXPECT_EQ(changedTokens(*net, b, 40), (std::vector<int64_t>{1, 5}));  // in no mask
}

TEST(LearningNetworks, TheStateNormalizationIsPartOfTheNetwork) {
  torch::manual_seed(0);
  const ObservationSpec spec = makeStateSpec();
  const auto net = makeNetwork(makeNet(NetKind::Mlp), spec, 0, 3);
  const ObservationBatch b = makeStateBatch(2, spec);
  const torch::Tensor plain = net->forward(b, {});
  net->setStateNormalization(torch::full({10}, 0.5), torch::full({10}, 2.0));
  ObservationBatch scaled;
  scaled.state = (b.state - 0.5) * 2;
  net->setStateNormalization(torch::zeros({10}), torch::ones({10}));
  const torch::Tensor expected = net->forward(scaled, {});
  net->setStateNormalization(torch::full({10}, 0.5), torch::full({10}, 2.0));
  EXPECT_TRUE(torch::allclose(net->forward(b, {}), expected));
  EXPECT_FALSE(torch::allclose(net->forward(b, {}), plain));
}

TransitionBatch makeTransitions(int64_t batch, const ObservationSpec& spec) {
  TransitionBatch t;
  t.obs = spec.isPointCloud() ? makeCloudBatch(batch, spec, 5) : makeStateBatch(batch, spec);
  t.next_obs = spec.isPointCloud() ? makeCloudBatch(batch, spec, 6) : makeStateBatch(batch, spec);
  t.actions = torch::rand({batch, int64_t(spec.action_dim)}) * 2 - 1;
  t.rewards = torch::randn({batch});
  t.dones = torch::zeros({batch});
  return t;
}

TEST(LearningAlgorithms, EveryAlgorithmStepsAndActsOnEveryNetwork) {
  for (const char* name : {"bc", "bcq", "td3bc"})
    for (NetKind kind : {NetKind::Mlp, NetKind::PointNet, NetKind::PnTransformer}) {
      SCOPED_TRACE(std::string(name) + " " + toString(kind));
      const ObservationSpec spec = kind == NetKind::Mlp ? makeStateSpec() : makeCloudSpec();
      AlgorithmOptions options = AlgorithmOptions::makeDefaults(name);
      options.eval_samples = 7;
      options.train_samples = 3;
      torch::manual_seed(0);
      auto algorithm = makeAlgorithm(options, makeNet(kind), spec, torch::kCPU);
      const TransitionBatch batch = makeTransitions(4, spec);
      for (int64_t i = 0; i < 2; ++i) {
        const std::vector<double> losses = algorithm->update(batch, i);
        ASSERT_EQ(losses.size(), algorithm->getLossNames().size());
        for (double l : losses) EXPECT_TRUE(std::isfinite(l));
      }
      at::Generator generator = at::detail::createCPUGenerator(1);
      const torch::Tensor a = algorithm->act(batch.obs, generator);
      EXPECT_EQ(a.sizes(), (std::vector<int64_t>{4, 3}));
      EXPECT_LE(a.abs().max().item<float>(), 1.0f);  // BC's too: tanh, as ManiSkill-Learn's
    }
}

TEST(LearningAlgorithms, BcFitsAFixedBatch) {
  torch::manual_seed(0);
  const ObservationSpec spec = makeStateSpec();
  auto bc = makeAlgorithm(AlgorithmOptions::makeDefaults("bc"), makeNet(NetKind::Mlp), spec, torch::kCPU);
  const TransitionBatch batch = makeTransitions(16, spec);
  const double first = bc->update(batch, 0)[0];
  double last = first;
  for (int64_t i = 1; i < 400; ++i) last = bc->update(batch, i)[0];
  EXPECT_LT(last, first / 100) << first << " -> " << last;
}

// Freezing the critics in the actor's step skips work, not math: the same
// weights, bit for bit, as the step that computes and discards the critics'
// parameter gradients.
TEST(LearningAlgorithms, FreezingTheCriticsInTheActorStepChangesNoWeight) {
  for (const char* name : {"sac", "td3bc", "bcq"}) {
    SCOPED_TRACE(name);
    const ObservationSpec spec = makeStateSpec();
    AlgorithmOptions options = AlgorithmOptions::makeDefaults(name);
    options.batch_size = 8;
    options.policy_delay = 1;
    std::vector<std::vector<torch::Tensor>> weights;
    for (bool freeze : {true, false}) {
      setActorStepFreezesCritics(freeze);
      torch::manual_seed(0);
      auto algorithm = makeAlgorithm(options, makeNet(NetKind::Mlp), spec, torch::kCPU);
      const TransitionBatch batch = makeTransitions(8, spec);
      for (int64_t i = 0; i < 5; ++i) algorithm->update(batch, i);
      std::vector<torch::Tensor> all;
      for (const auto& [network_name, network] : algorithm->getNetworks())
        for (const torch::Tensor& p : network->parameters()) {
          EXPECT_TRUE(p.requires_grad()) << network_name << " left frozen";
          all.push_back(p.detach().clone());
        }
      weights.push_back(all);
    }
    setActorStepFreezesCritics(true);
    ASSERT_EQ(weights[0].size(), weights[1].size());
    for (std::size_t i = 0; i < weights[0].size(); ++i) EXPECT_TRUE(torch::equal(weights[0][i], weights[1][i])) << i;
  }
}

TEST(LearningCheckpoints, ACheckpointRestoresTheSameActions) {
  const std::string path = (std::filesystem::temp_directory_path() / "manibench_checkpoint_test.pt").string();
  torch::manual_seed(0);
  const ObservationSpec spec = makeCloudSpec();
  AlgorithmOptions options = AlgorithmOptions::makeDefaults("td3bc");
  auto algorithm = makeAlgorithm(options, makeNet(NetKind::PointNet), spec, torch::kCPU);
  const TransitionBatch batch = makeTransitions(4, spec);
  for (int64_t i = 0; i < 3; ++i) algorithm->update(batch, i);
  CheckpointInfo info;
  info.iteration = 3;
  info.algorithm = options;
  info.network = makeNet(NetKind::PointNet);
  info.spec = spec;
  saveCheckpoint(path, info, *algorithm, {{"marker", torch::arange(3)}});
  const CheckpointInfo read = readCheckpointInfo(path);
  EXPECT_EQ(read.iteration, 3);
  EXPECT_EQ(read.algorithm.name, "td3bc");
  EXPECT_NO_THROW(read.spec.checkSame(spec, "read", "written"));
  torch::manual_seed(99);  // a different initialization, overwritten by the load
  LoadedCheckpoint loaded = loadCheckpoint(path, torch::kCPU, true, {"marker"});
  at::Generator g1 = at::detail::createCPUGenerator(1), g2 = at::detail::createCPUGenerator(1);
  EXPECT_TRUE(torch::equal(algorithm->act(batch.obs, g1), loaded.algorithm->act(batch.obs, g2)));
  EXPECT_TRUE(torch::equal(loaded.extras.at("marker"), torch::arange(3)));
  std::remove(path.c_str());
}

// The inference policy (what the torch_policy plugin runs: inference mode,
// the process's freed memory kept) acts as the algorithm's own act() on the
// same inputs, bit for bit, step after step and across a reset: BC with
// stacked observations and actions (the history it keeps between steps)
// and BCQ (its sampled latents from the policy's generator).
TEST(LearningCheckpoints, TheInferencePolicyActsAsTheAlgorithmBitForBit) {
  const std::string path = (std::filesystem::temp_directory_path() / "manibench_inference_test.pt").string();
  const ObservationSpec spec = makeCloudSpec();
  for (const std::string name : {"bc", "bcq"}) {
    SCOPED_TRACE(name);
    torch::manual_seed(0);
    CheckpointInfo info;
    info.algorithm = AlgorithmOptions::makeDefaults(name, spec.mode);
    info.algorithm.eval_samples = 7;
    info.network = makeNet(name == "bc" ? NetKind::PointNet : NetKind::PnTransformer);
    if (name == "bc") {
      info.network.history = 2;
      info.network.action_history = 2;
    }
    info.spec = spec;
    auto algorithm = makeAlgorithm(info.algorithm, info.network, spec, torch::kCPU);
    saveCheckpoint(path, info, *algorithm, {});
    InferenceOptions options;
    options.checkpoint = path;
    const std::unique_ptr<InferencePolicy> policy = loadInferencePolicy(options, spec);
    InputHistory history(info.network, spec);
    for (int episode = 0; episode < 2; ++episode) {
      policy->reset(uint64_t(10 + episode));
      history.reset();
      at::Generator generator = at::detail::createCPUGenerator(uint64_t(10 + episode));
      for (int64_t step = 0; step < 3; ++step) {
        const ObservationBatch obs = makeCloudBatch(1, spec, uint64_t(100 * episode + step));
        ObservationBatch input = obs;
        input.state = history.makeInput(obs.state, step);
        const torch::Tensor expected = algorithm->act(input, generator).squeeze(0);
        history.setAction(expected);
        EXPECT_TRUE(torch::equal(policy->act(obs), expected)) << "episode " << episode << ", step " << step;
      }
    }
  }
  std::remove(path.c_str());
}

// The parameters of every network of an algorithm, detached copies.
std::vector<torch::Tensor> copyParameters(const Algorithm& algorithm) {
  std::vector<torch::Tensor> all;
  for (const auto& [name, network] : algorithm.getNetworks())
    for (const torch::Tensor& p : network->parameters()) all.push_back(p.detach().clone());
  return all;
}

// A checkpoint loads onto the device asked for, through the map at load
// that a CUDA-trained checkpoint evaluated on the CPU takes (CPU to CPU
// here; CUDA to CPU and back where this libtorch sees a GPU), optimizers,
// extras (always on the CPU) and all.
TEST(LearningCheckpoints, ACheckpointLoadsOntoTheDeviceAskedFor) {
  const std::string path = (std::filesystem::temp_directory_path() / "manibench_device_test.pt").string();
  const ObservationSpec spec = makeCloudSpec();
  const AlgorithmOptions options = AlgorithmOptions::makeDefaults("td3bc");
  std::vector<torch::Device> devices{torch::Device("cpu")};
  if (torch::cuda::is_available()) devices.emplace_back("cuda");
  for (const torch::Device& from : devices)
    for (const torch::Device& to : devices) {
      SCOPED_TRACE(from.str() + " -> " + to.str());
      torch::manual_seed(0);
      auto algorithm = makeAlgorithm(options, makeNet(NetKind::PointNet), spec, from);
      const TransitionBatch batch = makeTransitions(4, spec);
      for (int64_t i = 0; i < 2; ++i) algorithm->update(batch.to(from), i);
      CheckpointInfo info;
      info.algorithm = options;
      info.network = makeNet(NetKind::PointNet);
      info.spec = spec;
      std::map<std::string, torch::Tensor> extras{{"marker", torch::arange(3).to(from)}};
      addGeneratorStates(extras, from);
      EXPECT_EQ(extras.count(kCudaGeneratorExtra), from.is_cuda() ? 1u : 0u);
      saveCheckpoint(path, info, *algorithm, extras);
      LoadedCheckpoint loaded = loadCheckpoint(path, to, true, {"marker", kCpuGeneratorExtra, kCudaGeneratorExtra});
      for (const auto& [name, network] : loaded.algorithm->getNetworks()) {
        // (The type: a tensor's device has an index, "cuda:0", where "cuda" has none.)
        for (const torch::Tensor& p : network->parameters()) EXPECT_EQ(p.device().type(), to.type()) << name;
        for (const torch::Tensor& b : network->buffers()) EXPECT_EQ(b.device().type(), to.type()) << name;
      }
      for (const auto& [name, tensor] : loaded.extras) EXPECT_TRUE(tensor.is_cpu()) << name;
      EXPECT_EQ(loaded.extras.count(kCudaGeneratorExtra), from.is_cuda() ? 1u : 0u);
      EXPECT_TRUE(torch::equal(loaded.extras.at("marker"), torch::arange(3)));
      const std::vector<torch::Tensor> saved = copyParameters(*algorithm), read = copyParameters(*loaded.algorithm);
      ASSERT_EQ(saved.size(), read.size());
      for (std::size_t i = 0; i < saved.size(); ++i) EXPECT_TRUE(torch::equal(saved[i].cpu(), read[i].cpu())) << i;
      if (from != to) continue;  // the target noise of the next step comes from another generator
      // The optimizers' moments came along: one more step from either is the same step.
      torch::manual_seed(5);
      algorithm->update(batch.to(from), 3);
      torch::manual_seed(5);
      loaded.algorithm->update(batch.to(to), 3);
      const std::vector<torch::Tensor> a = copyParameters(*algorithm), b = copyParameters(*loaded.algorithm);
      // (CUDA's backward of a gather adds with atomics, in no fixed order.)
      for (std::size_t i = 0; i < a.size(); ++i)
        EXPECT_TRUE(from.is_cpu() ? torch::equal(a[i], b[i]) : torch::allclose(a[i], b[i], 1e-5, 1e-6)) << i;
    }
  std::remove(path.c_str());
}

// The saved random state of every device in use sets it back.
TEST(LearningCheckpoints, GeneratorStatesRestoreTheDraws) {
  std::vector<torch::Device> devices{torch::Device("cpu")};
  if (torch::cuda::is_available()) devices.emplace_back("cuda");
  for (const torch::Device& device : devices) {
    SCOPED_TRACE(device.str());
    torch::manual_seed(3);
    std::map<std::string, torch::Tensor> extras;
    addGeneratorStates(extras, device);
    const torch::Tensor cpu = torch::rand({5}), on_device = torch::rand({5}, torch::TensorOptions(device));
    torch::manual_seed(4);
    restoreGeneratorStates(extras, device);
    EXPECT_TRUE(torch::equal(torch::rand({5}), cpu));
    EXPECT_TRUE(torch::equal(torch::rand({5}, torch::TensorOptions(device)), on_device));
  }
}

TEST(LearningDevices, ADeviceThisLibtorchCannotUseIsAClearError) {
  EXPECT_EQ(parseDevice("cpu"), torch::Device(torch::kCPU));
  EXPECT_THROW(parseDevice("gpu"), LearningError);
  if (torch::cuda::is_available()) GTEST_SKIP() << "this libtorch sees a GPU";
  try {
    parseDevice("cuda");
    FAIL() << "cuda was accepted without CUDA";
  } catch (const LearningError& e) {
    EXPECT_NE(std::string(e.what()).find("has no CUDA"), std::string::npos) << e.what();
  }
  InferenceOptions options;
  options.checkpoint = "/nonexistent/checkpoint.pt";
  options.device = "cuda";
  EXPECT_THROW(loadInferencePolicy(options, makeCloudSpec()), LearningError);
}

// BCQ's acting samples come from the policy's generator, whichever device
// its networks are on: the same seed, the same latents and actions.
TEST(LearningAlgorithms, BcqSamplesWithTheActingGeneratorOnEveryDevice) {
  const ObservationSpec spec = makeStateSpec();
  AlgorithmOptions options = AlgorithmOptions::makeDefaults("bcq");
  options.eval_samples = 20;
  torch::manual_seed(0);
  auto bcq = makeAlgorithm(options, makeNet(NetKind::Mlp), spec, torch::kCPU);
  const ObservationBatch obs = makeStateBatch(3, spec);
  at::Generator g1 = at::detail::createCPUGenerator(7), g2 = at::detail::createCPUGenerator(7),
                g3 = at::detail::createCPUGenerator(8);
  const torch::Tensor a = bcq->act(obs, g1);
  EXPECT_TRUE(torch::equal(a, bcq->act(obs, g2)));
  EXPECT_FALSE(torch::equal(a, bcq->act(obs, g3)));
  if (!torch::cuda::is_available()) return;
  for (const auto& [name, network] : bcq->getNetworks()) network->to(torch::kCUDA);
  at::Generator g4 = at::detail::createCPUGenerator(7);
  EXPECT_TRUE(torch::allclose(bcq->act(obs.to(torch::kCUDA), g4).cpu(), a, 1e-4, 1e-5));
}

// ManiSkill-Learn's settings are the defaults; what older checkpoints ran
// reads back as they ran it.
TEST(LearningAlgorithms, ManiSkillLearnsSettingsAndTheOlderOnes) {
  const NetOptions offline = NetOptions::makeDefaults("td3bc"), bc = NetOptions::makeDefaults("bc");
  EXPECT_EQ(std::vector<int64_t>({offline.layers, offline.width, offline.ff}), std::vector<int64_t>({2, 192, 768}));
  EXPECT_EQ(std::vector<int64_t>({bc.layers, bc.width, bc.ff}), std::vector<int64_t>({6, 256, 1024}));
  EXPECT_EQ(AlgorithmOptions::makeDefaults("td3bc", "pointcloud").weight_decay, 5e-6);
  EXPECT_EQ(AlgorithmOptions::makeDefaults("bc", "state").weight_decay, 0);
  EXPECT_EQ(AlgorithmOptions::makeDefaults("bc", "state").lr, 1e-3);
  EXPECT_EQ(AlgorithmOptions::makeDefaults("bc", "pointcloud").lr, 3e-4);
  YAML::Node a, n;
  AlgorithmOptions::makeDefaults("sac").writeYaml(a);
  makeNet(NetKind::PnTransformer).writeYaml(n);
  EXPECT_TRUE(AlgorithmOptions::readYaml(a).bc_tanh);
  EXPECT_FALSE(AlgorithmOptions::readYaml(a).temperature_gradient_log);
  EXPECT_FALSE(NetOptions::readYaml(n).transformer_masks);
  a.remove("bc_tanh");
  a.remove("temperature_gradient_log");
  n.remove("transformer_masks");
  EXPECT_FALSE(AlgorithmOptions::readYaml(a).bc_tanh);
  EXPECT_TRUE(AlgorithmOptions::readYaml(a).temperature_gradient_log);
  EXPECT_TRUE(NetOptions::readYaml(n).transformer_masks);
  // The transformer's PointNets see xyz, rgb and the state, not the K mask channels.
  const ObservationSpec spec = makeCloudSpec();
  NetOptions with = makeNet(NetKind::PnTransformer);
  with.transformer_masks = true;
  const int64_t k = spec.mask_count, width = with.width;
  EXPECT_EQ(countParameters(*makeNetwork(with, spec, 0, 3)) -
                countParameters(*makeNetwork(makeNet(NetKind::PnTransformer), spec, 0, 3)),
            (k + 2) * k * width);
  // SAC starts at alpha = 1 (log alpha = 0).
  torch::manual_seed(0);
  auto sac = makeAlgorithm(AlgorithmOptions::makeDefaults("sac"), makeNet(NetKind::Mlp), makeStateSpec(), torch::kCPU);
  EXPECT_EQ(sac->update(makeTransitions(8, makeStateSpec()), 0)[2], 1.0);
}

TEST(LearningCheckpoints, FilesThatAreNotCheckpointsAreClearErrors) {
  const auto dir = std::filesystem::temp_directory_path();
  try {
    readCheckpointInfo((dir / "manibench_no_such_checkpoint.pt").string());
    FAIL();
  } catch (const LearningError& e) {
    EXPECT_NE(std::string(e.what()).find("no such checkpoint"), std::string::npos) << e.what();
  }
  const std::string text = (dir / "manibench_not_a_checkpoint.pt").string();
  std::ofstream(text) << "hello";
  try {
    readCheckpointInfo(text);
    FAIL();
  } catch (const LearningError& e) {
    EXPECT_NE(std::string(e.what()).find("manibench_not_a_checkpoint.pt"), std::string::npos) << e.what();
  }
  std::remove(text.c_str());
}

TEST(LearningSpec, DifferentLayoutsAreErrorsNamingBoth) {
  ObservationSpec a = makeStateSpec(), b = makeStateSpec();
  b.state_segments[1].name = "c";
  try {
    a.checkSame(b, "the checkpoint X", "the demonstrations Y");
    FAIL();
  } catch (const LearningError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("state layout"), std::string::npos) << m;
    EXPECT_NE(m.find("the checkpoint X: Synthetic-v0, state, state 10 [a 4, b 6]"), std::string::npos) << m;
    EXPECT_NE(m.find("the demonstrations Y: Synthetic-v0, state, state 10 [a 4, c 6]"), std::string::npos) << m;
  }
  b = makeStateSpec();
  b.task = "Other-v0";
  EXPECT_THROW(a.checkSame(b, "x", "y"), LearningError);
  EXPECT_NO_THROW(a.checkSame(makeStateSpec(), "x", "y"));
}

// A mobile-robot layout as the tasks word it (MoveBucket-v0's kinds).
ObservationSpec makeMobileSpec() {
  ObservationSpec s;
  s.task = "Mobile-v0";
  s.mode = "state";
  s.state_segments = {{"fingertip_positions", 0, 6, "finger pad centres, world (m)"},
                      {"base_position", 6, 2, "x, y of base_link, world (m)"},
                      {"base_yaw", 8, 1, "heading (rad)"},
                      {"base_velocity", 9, 2, "world x, y (m/s)"},
                      {"joint_positions", 11, 3, "robot q, actuated joint order"},
                      {"bucket_pose", 14, 7, "bucket frame: position, quaternion wxyz"},
                      {"bucket_ang_velocity", 21, 3, "world (rad/s)"},
                      {"joint_axis", 24, 3, "world; q grows turning about it"},
                      {"rim", 27, 3, "half widths (m)"}};
  s.state_dim = 30;
  s.action_dim = 2;
  s.action_segments = {{"base", 0, 2}};
  return s;
}

TEST(LearningRobotFrame, ThePlanFollowsTheSegmentsNamesAndDescriptions) {
  const RobotFrameInputs plan = planRobotFrameInputs(makeMobileSpec());
  EXPECT_EQ(plan.base_position, 6u);
  EXPECT_EQ(plan.base_yaw, 8u);
  using K = RobotFrameInputs::Kind;
  const std::vector<RobotFrameInputs::Entry> expected{{"fingertip_positions", K::Points, 0, 6},
                                                      {"base_velocity", K::PlanarVector, 9, 2},
                                                      {"bucket_pose", K::Pose, 14, 7},
                                                      {"bucket_ang_velocity", K::Vectors, 21, 3},
                                                      {"joint_axis", K::Vectors, 24, 3}};
  EXPECT_EQ(plan.entries, expected) << plan.describe();
  EXPECT_EQ(plan.calcDim(), 21);
  NetOptions options;  // the plan travels with the network's options (train.yaml, checkpoints)
  options.robot_frame = plan;
  YAML::Node node;
  options.writeYaml(node);
  EXPECT_EQ(NetOptions::readYaml(YAML::Load(YAML::Dump(node))).robot_frame, plan) << YAML::Dump(node);
  EXPECT_TRUE(NetOptions::readYaml(YAML::Load(YAML::Dump(node))).hasExtraStateInputs());

  ObservationSpec fixed = makeMobileSpec();
  fixed.state_segments.erase(fixed.state_segments.begin() + 2);  // no base_yaw
  try {
    planRobotFrameInputs(fixed);
    FAIL();
  } catch (const LearningError& e) {
    EXPECT_NE(std::string(e.what()).find("base_yaw"), std::string::npos) << e.what();
  }
}

TEST(LearningRobotFrame, FeaturesAreTheWorldSeenFromTheBase) {
  const RobotFrameInputs plan = planRobotFrameInputs(makeMobileSpec());
  // The base at (1, 2) facing +y; a finger pad at (1, 3, 0.5) is 1 m ahead.
  torch::Tensor s = torch::zeros({1, 30});
  s[0][0] = 1; s[0][1] = 3; s[0][2] = 0.5;
  s[0][6] = 1; s[0][7] = 2; s[0][8] = float(M_PI / 2);
  s[0][9] = 0.0; s[0][10] = 0.3;  // moving along world +y: forward
  s[0][17] = 1.0;                  // the bucket's identity orientation (w = 1)
  const torch::Tensor f = calcRobotFrameFeatures(plan, s);
  ASSERT_EQ(f.size(1), plan.calcDim());
  EXPECT_NEAR(f[0][0].item<float>(), 1.0, 1e-6);
  EXPECT_NEAR(f[0][1].item<float>(), 0.0, 1e-6);
  EXPECT_NEAR(f[0][2].item<float>(), 0.5, 1e-6);
  EXPECT_NEAR(f[0][6].item<float>(), 0.3, 1e-6);  // base_velocity: forward
  EXPECT_NEAR(f[0][7].item<float>(), 0.0, 1e-6);
  // The world-aligned bucket is turned by -90 degrees about z, w kept >= 0.
  EXPECT_NEAR(f[0][11].item<float>(), std::sqrt(0.5), 1e-6);
  EXPECT_NEAR(f[0][14].item<float>(), -std::sqrt(0.5), 1e-6);
}

TEST(LearningRobotFrame, FeaturesDoNotChangeWhenTheWholeSceneMovesAndTurns) {
  const RobotFrameInputs plan = planRobotFrameInputs(makeMobileSpec());
  torch::manual_seed(3);
  torch::Tensor s = torch::randn({16, 30}, torch::kFloat64);
  for (int64_t q : {17}) {  // a unit quaternion
    const torch::Tensor quat = s.slice(1, q, q + 4);
    s.slice(1, q, q + 4).copy_(quat / quat.norm(2, 1, true));
  }
  // Turn everything by 0.7 rad about z and shift it by (3, -2).
  const double a = 0.7, c = std::cos(a), n = std::sin(a);
  torch::Tensor moved = s.clone();
  auto turnColumns = [&](int64_t x, bool shift) {
    const torch::Tensor px = s.select(1, x), py = s.select(1, x + 1);
    moved.select(1, x).copy_(c * px - n * py + (shift ? 3.0 : 0.0));
    moved.select(1, x + 1).copy_(n * px + c * py + (shift ? -2.0 : 0.0));
  };
  for (int64_t x : {0, 3, 6, 14}) turnColumns(x, true);  // points, the base, the pose's position
  for (int64_t x : {9, 21, 24}) turnColumns(x, false);    // vectors
  moved.select(1, 8) += a;                                // the base's heading
  const torch::Tensor qw = s.select(1, 17), qz = s.select(1, 20), qx = s.select(1, 18), qy = s.select(1, 19);
  const double hw = std::cos(a / 2), hz = std::sin(a / 2);  // (hw, 0, 0, hz) * q
  moved.select(1, 17).copy_(hw * qw - hz * qz);
  moved.select(1, 18).copy_(hw * qx - hz * qy);
  moved.select(1, 19).copy_(hw * qy + hz * qx);
  moved.select(1, 20).copy_(hw * qz + hz * qw);
  const torch::Tensor before = calcRobotFrameFeatures(plan, s), after = calcRobotFrameFeatures(plan, moved);
  EXPECT_TRUE(torch::allclose(before, after, 1e-5, 1e-5)) << (before - after).abs().max();
  // The world-frame state itself did change.
  EXPECT_FALSE(torch::allclose(s, moved, 1e-3, 1e-3));
}

}  // namespace
}  // namespace manibench::learning
