// manibench_learning_bench: training iterations per second of the learning
// module's networks (BC updates: forward, MSE, backward, Adam) and the
// latency of one action, on synthetic batches shaped like
// OpenCabinetDrawer-v0's (state 80, agent 51, 1200 points, 3 masks, action
// 11). bench/learning_speed.py runs it beside the same networks written in
// python3-torch on the same libtorch (docs/learning-results.md has the numbers).
// `--algorithm sac|td3bc|bcq` times those algorithms' gradient steps instead
// (any network), and `--pairs N` alternates N times between the actor step
// that freezes the critics and the reference that does not, printing each
// pair (the VM is noisy: only pairs measured side by side compare).
// `--device cuda` trains there (the batch is made once, on the device: the
// networks' speed, not the loader's); `--checkpoint PATH` then saves the
// network, loads it onto the CPU and prints how far the CPU's actions are
// from the device's (the round trip of a checkpoint trained on a GPU).
// `--act` times acting instead: one observation at a time, as the
// torch_policy plugin acts, for BC (mlp, pointnet, pn_transformer), TD3+BC
// and BCQ (pn_transformer) with ManiSkill-Learn's defaults, in ms per step,
// and prints each action in hexadecimal floats (so two builds' actions can
// be compared bit for bit: docs/learning-results.md, "Acting").
#include <manibench/learning/algorithms.hpp>
#include <manibench/learning/checkpoint.hpp>
#include <manibench/learning/compute.hpp>
#include <manibench/learning/inference.hpp>

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <map>
#include <string>
#include <vector>

namespace ml = manibench::learning;

namespace {

struct Options {
  std::string net = "mlp";
  int64_t batch = 128;
  int threads = 2;
  double seconds = 20;
  bool definition = false;
  std::string algorithm = "bc";
  int pairs = 0;
  std::string device = "cpu";
  std::string checkpoint;  // the round trip's file (empty: none)
  bool act = false;
  std::string only;  // --act: only this "algorithm/net" (empty: all five)
};

ml::ObservationSpec makeSpec(bool cloud) {
  ml::ObservationSpec s;
  s.task = "OpenCabinetDrawer-v0";
  s.mode = cloud ? "pointcloud" : "state";
  s.state_dim = cloud ? 51 : 80;
  s.action_dim = 11;
  s.point_count = cloud ? 1200 : 0;
  s.mask_count = cloud ? 3 : 0;
  return s;
}

// Masks as D.1 leaves them on a drawer: handle (100 points) inside the
// target link (400), the robot (400), then 400 points in no mask.
ml::ObservationBatch makeBatch(const ml::ObservationSpec& spec, int64_t batch) {
  ml::ObservationBatch b;
  b.state = torch::randn({batch, int64_t(spec.state_dim)});
  if (!spec.isPointCloud()) return b;
  const int64_t n = spec.point_count;
  b.xyz = torch::rand({batch, n, 3});
  b.rgb = torch::rand({batch, n, 3});
  b.seg = torch::zeros({batch, n, 3});
  b.seg.slice(1, 0, 100).select(2, 0).fill_(1);
  b.seg.slice(1, 0, 400).select(2, 1).fill_(1);
  b.seg.slice(1, 400, 800).select(2, 2).fill_(1);
  b.valid = ml::calcValidPoints(b.xyz, b.rgb, b.seg);
  return b;
}

ml::TransitionBatch makeTransitions(const ml::ObservationSpec& spec, int64_t batch) {
  ml::TransitionBatch b;
  b.obs = makeBatch(spec, batch);
  b.next_obs = makeBatch(spec, batch);
  b.actions = torch::rand({batch, int64_t(spec.action_dim)}) * 2 - 1;
  b.rewards = torch::randn({batch});
  b.dones = (torch::rand({batch}) < 0.01).to(torch::kFloat32);
  return b;
}

// Gradient steps per second of `algorithm` for `seconds` (after two untimed;
// every update returns its losses with .item(), which waits for a device).
double timeUpdates(ml::Algorithm& algorithm, const ml::TransitionBatch& batch, double seconds) {
  using clock = std::chrono::steady_clock;
  for (int i = 0; i < 2; ++i) algorithm.update(batch, i);
  int64_t iterations = 0;
  const auto start = clock::now();
  double elapsed = 0;
  while (elapsed < seconds || iterations < 3) {
    algorithm.update(batch, iterations++);
    elapsed = std::chrono::duration<double>(clock::now() - start).count();
  }
  return double(iterations) / elapsed;
}

// The online and actor-critic algorithms: frozen critics against the reference, in pairs.
int runActorCritic(const Options& o) {
  ml::setUpTrainingCompute(o.threads);
  const torch::Device device = ml::parseDevice(o.device);
  torch::manual_seed(0);
  ml::NetOptions net = ml::NetOptions::makeDefaults(o.algorithm);
  net.kind = ml::parseNetKind(o.net);
  const ml::ObservationSpec spec = makeSpec(net.kind != ml::NetKind::Mlp);
  ml::AlgorithmOptions options = ml::AlgorithmOptions::makeDefaults(o.algorithm, spec.mode);
  options.batch_size = o.batch;
  auto frozen = ml::makeAlgorithm(options, net, spec, device);
  auto reference = ml::makeAlgorithm(options, net, spec, device);
  const ml::TransitionBatch batch = makeTransitions(spec, o.batch).to(device);
  double sum_frozen = 0, sum_reference = 0;
  for (int pair = 0; pair < std::max(o.pairs, 1); ++pair) {
    ml::setActorStepFreezesCritics(true);
    const double a = timeUpdates(*frozen, batch, o.seconds);
    double b = 0;
    if (o.pairs > 0) {
      ml::setActorStepFreezesCritics(false);
      b = timeUpdates(*reference, batch, o.seconds);
    }
    sum_frozen += a;
    sum_reference += b;
    if (o.pairs > 0)
      std::printf("pair %d: frozen critics %.3f updates/s, reference %.3f updates/s (x%.3f)\n", pair, a, b, a / b);
    else
      std::printf("%s %s batch %lld threads %d device %s: %.3f updates/s\n", o.algorithm.c_str(), o.net.c_str(),
                  (long long)o.batch, o.threads, o.device.c_str(), a);
  }
  if (o.pairs > 1)
    std::printf("%s batch %lld threads %d, mean of %d pairs: frozen %.3f, reference %.3f updates/s (x%.3f)\n",
                o.algorithm.c_str(), (long long)o.batch, o.threads, o.pairs, sum_frozen / o.pairs,
                sum_reference / o.pairs, sum_frozen / sum_reference);
  std::fprintf(stderr, "%s\n", ml::describeCompute(ml::calcComputeInfo(), device).c_str());
  return 0;
}

// Saves `algorithm` (trained on `device`), loads it onto the CPU, and prints
// the largest difference between the two's actions on the same observations.
void roundTrip(const ml::Algorithm& algorithm, const ml::NetOptions& net, const ml::ObservationSpec& spec,
               const std::string& path, const torch::Device& device) {
  ml::CheckpointInfo info;
  info.algorithm = algorithm.getOptions();
  info.network = net;
  info.spec = spec;
  std::map<std::string, torch::Tensor> extras;
  ml::addGeneratorStates(extras, device);
  ml::saveCheckpoint(path, info, algorithm, extras);
  ml::LoadedCheckpoint cpu = ml::loadCheckpoint(path, torch::kCPU, true, {ml::kCpuGeneratorExtra, ml::kCudaGeneratorExtra});
  ml::LoadedCheckpoint there = ml::loadCheckpoint(path, device, false);
  const ml::ObservationBatch obs = makeBatch(spec, 4);
  at::Generator g1 = at::detail::createCPUGenerator(0), g2 = at::detail::createCPUGenerator(0);
  const torch::Tensor a = there.algorithm->act(obs.to(device), g1).cpu(), b = cpu.algorithm->act(obs, g2);
  bool all_cpu = true;
  for (const auto& [name, network] : cpu.algorithm->getNetworks())
    for (const torch::Tensor& p : network->parameters()) all_cpu = all_cpu && p.is_cpu();
  std::printf("round trip %s -> cpu: parameters on the cpu %s, CUDA random state %s, largest action difference %.3g\n",
              device.str().c_str(), all_cpu ? "yes" : "NO",
              cpu.extras.count(ml::kCudaGeneratorExtra) ? "saved" : "absent", (a - b).abs().max().item<double>());
}

// ms per step at batch 1 of each network, through what the torch_policy
// plugin runs (a checkpoint saved and loaded by loadInferencePolicy, which
// sets the threads; no other process-wide setting), and its action.
int runActing(const Options& o) {
  const std::vector<std::pair<std::string, std::string>> all = {
      {"bc", "mlp"}, {"bc", "pointnet"}, {"bc", "pn_transformer"}, {"td3bc", "pn_transformer"}, {"bcq", "pn_transformer"}};
  const std::string path = "/tmp/manibench_act_bench_" + std::to_string(getpid()) + ".pt";
  for (const auto& [algorithm, net_name] : all) {
    if (!o.only.empty() && o.only != algorithm + "/" + net_name) continue;
    torch::manual_seed(0);
    ml::NetOptions net = ml::NetOptions::makeDefaults(algorithm);
    net.kind = ml::parseNetKind(net_name);
    const ml::ObservationSpec spec = makeSpec(net.kind != ml::NetKind::Mlp);
    {
      ml::CheckpointInfo info;
      info.algorithm = ml::AlgorithmOptions::makeDefaults(algorithm, spec.mode);
      info.network = net;
      info.spec = spec;
      auto trained = ml::makeAlgorithm(info.algorithm, net, spec, torch::kCPU);
      ml::saveCheckpoint(path, info, *trained, {});
    }
    ml::InferenceOptions options;
    options.checkpoint = path;
    options.threads = o.threads;
    const std::unique_ptr<ml::InferencePolicy> policy = ml::loadInferencePolicy(options, spec);
    std::remove(path.c_str());
    const ml::ObservationBatch one = makeBatch(spec, 1);
    policy->reset(0);
    for (int i = 0; i < 2; ++i) policy->act(one);
    using clock = std::chrono::steady_clock;
    int64_t acts = 0;
    const auto start = clock::now();
    double elapsed = 0;
    while (elapsed < o.seconds || acts < 3) {
      policy->act(one);
      ++acts;
      elapsed = std::chrono::duration<double>(clock::now() - start).count();
    }
    policy->reset(7);
    const torch::Tensor action = policy->act(one).contiguous();
    std::printf("act %s %s threads %d: %.3f ms per step (%lld steps), action", algorithm.c_str(), net_name.c_str(),
                o.threads, 1e3 * elapsed / double(acts), (long long)acts);
    const float* a = action.data_ptr<float>();
    for (int64_t i = 0; i < action.numel(); ++i) std::printf(" %a", double(a[i]));
    std::printf("\n");
    std::fflush(stdout);
  }
  return 0;
}

int run(const Options& o) {
  if (o.act) return runActing(o);
  if (o.algorithm != "bc") return runActorCritic(o);
  ml::setUpTrainingCompute(o.threads);  // as the trainer: without kept memory PN+T ran 0.31 it/s here, with it 0.46 (one thread)
  ml::setPointNetDefinitionMode(o.definition);
  const torch::Device device = ml::parseDevice(o.device);
  torch::manual_seed(0);
  ml::NetOptions net;
  net.kind = ml::parseNetKind(o.net);
  const ml::ObservationSpec spec = makeSpec(net.kind != ml::NetKind::Mlp);
  auto bc = ml::makeAlgorithm(ml::AlgorithmOptions::makeDefaults("bc", spec.mode), net, spec, device);
  ml::TransitionBatch batch;
  batch.obs = makeBatch(spec, o.batch).to(device);
  batch.actions = (torch::rand({o.batch, 11}) * 2 - 1).to(device);
  using clock = std::chrono::steady_clock;
  for (int i = 0; i < 2; ++i) bc->update(batch, i);
  int64_t iterations = 0;
  const auto start = clock::now();
  double elapsed = 0;
  while (elapsed < o.seconds || iterations < 3) {
    bc->update(batch, iterations++);
    elapsed = std::chrono::duration<double>(clock::now() - start).count();
  }
  // One observation at a time, as the policy plugin acts.
  const ml::ObservationBatch one = makeBatch(spec, 1).to(device);
  at::Generator generator = at::detail::createCPUGenerator(0);
  for (int i = 0; i < 3; ++i) bc->act(one, generator).cpu();  // waits for a device, as the policy plugin does
  int64_t acts = 0;
  const auto act_start = clock::now();
  double act_elapsed = 0;
  while (act_elapsed < std::min(5.0, o.seconds) || acts < 10) {
    bc->act(one, generator).cpu();  // waits for a device, as the policy plugin does
    ++acts;
    act_elapsed = std::chrono::duration<double>(clock::now() - act_start).count();
  }
  std::printf("manibench %s batch %lld threads %d device %s%s: %.3f it/s (%lld iterations in %.1f s), act %.3f ms\n",
              o.net.c_str(), (long long)o.batch, o.threads, o.device.c_str(), o.definition ? " (definition)" : "",
              double(iterations) / elapsed, (long long)iterations, elapsed, 1e3 * act_elapsed / double(acts));
  std::fprintf(stderr, "%s\n", ml::describeCompute(ml::calcComputeInfo(), device).c_str());
  if (!o.checkpoint.empty()) roundTrip(*bc, net, spec, o.checkpoint, device);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) throw std::runtime_error(a + " needs a value");
      return argv[++i];
    };
    if (a == "--net") o.net = next();
    else if (a == "--batch") o.batch = std::stoll(next());
    else if (a == "--threads") o.threads = std::stoi(next());
    else if (a == "--seconds") o.seconds = std::stod(next());
    else if (a == "--definition") o.definition = true;
    else if (a == "--algorithm") o.algorithm = next();
    else if (a == "--pairs") o.pairs = std::stoi(next());
    else if (a == "--device") o.device = next();
    else if (a == "--checkpoint") o.checkpoint = next();
    else if (a == "--act") o.act = true;
    else if (a == "--only") o.only = next();
    else {
      std::cerr << "usage: manibench_learning_bench [--net mlp|pointnet|pn_transformer] [--batch N] "
                   "[--threads N] [--seconds S] [--definition] [--device cpu|cuda] [--checkpoint PATH]\n"
                   "       manibench_learning_bench --algorithm sac|td3bc|bcq [--net ...] [--batch N] [--threads N] "
                   "[--seconds S] [--pairs N] [--device cpu|cuda]\n"
                   "       manibench_learning_bench --act [--only ALGORITHM/NET] [--threads N] [--seconds S]\n";
      return 2;
    }
  }
  try {
    return run(o);
  } catch (const std::exception& e) {
    std::cerr << "manibench_learning_bench: " << e.what() << "\n";
    return 1;
  }
}
