// manibench_learning_bench: training iterations per second of the learning
// module's networks (BC updates: forward, MSE, backward, Adam) and the
// latency of one action, on synthetic batches shaped like
// OpenCabinetDrawer-v0's (state 80, agent 51, 1200 points, 3 masks, action
// 11). bench/learning_speed.py runs it beside the same networks written in
// python3-torch on the same libtorch (docs/learning.md has the numbers).
#include <manibench/learning/algorithms.hpp>
#include <manibench/learning/compute.hpp>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <string>

namespace ml = manibench::learning;

namespace {

struct Options {
  std::string net = "mlp";
  int64_t batch = 128;
  int threads = 2;
  double seconds = 20;
  bool definition = false;
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

int run(const Options& o) {
  ml::setComputeThreads(o.threads);
  ml::setPointNetDefinitionMode(o.definition);
  torch::manual_seed(0);
  ml::NetOptions net;
  net.kind = ml::parseNetKind(o.net);
  const ml::ObservationSpec spec = makeSpec(net.kind != ml::NetKind::Mlp);
  auto bc = ml::makeAlgorithm(ml::AlgorithmOptions::makeDefaults("bc"), net, spec, torch::kCPU);
  ml::TransitionBatch batch;
  batch.obs = makeBatch(spec, o.batch);
  batch.actions = torch::rand({o.batch, 11}) * 2 - 1;
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
  const ml::ObservationBatch one = makeBatch(spec, 1);
  at::Generator generator = at::detail::createCPUGenerator(0);
  for (int i = 0; i < 3; ++i) bc->act(one, generator);
  int64_t acts = 0;
  const auto act_start = clock::now();
  double act_elapsed = 0;
  while (act_elapsed < std::min(5.0, o.seconds) || acts < 10) {
    bc->act(one, generator);
    ++acts;
    act_elapsed = std::chrono::duration<double>(clock::now() - act_start).count();
  }
  std::printf("manibench %s batch %lld threads %d%s: %.3f it/s (%lld iterations in %.1f s), act %.3f ms\n",
              o.net.c_str(), (long long)o.batch, o.threads, o.definition ? " (definition)" : "",
              double(iterations) / elapsed, (long long)iterations, elapsed, 1e3 * act_elapsed / double(acts));
  std::fprintf(stderr, "%s\n", ml::describeCompute(ml::calcComputeInfo(), torch::kCPU).c_str());
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
    else {
      std::cerr << "usage: manibench_learning_bench [--net mlp|pointnet|pn_transformer] [--batch N] "
                   "[--threads N] [--seconds S] [--definition]\n";
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
