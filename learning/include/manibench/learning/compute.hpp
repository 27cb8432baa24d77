// Where the numbers are computed: which BLAS libtorch ends up calling (Debian's
// libtorch calls the system's libblas.so.3, which is the reference BLAS
// unless libopenblas0-pthread is installed: a PointNet iteration measured
// 55 s with it, 2.6 s with OpenBLAS), how many threads libtorch and
// OpenBLAS use, and the device.
#pragma once

#include <torch/torch.h>

#include <string>

namespace manibench::learning {

struct ComputeInfo {
  std::string blas;          // "OpenBLAS 0.3.21 ... (pthread)", "reference BLAS (libblas3)", ...
  std::string blas_library;  // the file libblas.so.3 resolves to
  bool blas_is_reference = false;
  int blas_threads = 0;      // OpenBLAS's pool (0: not OpenBLAS)
  int torch_threads = 0;     // libtorch's intra-op threads
  std::string torch_version;
  bool cuda_available = false;
};

// Sets libtorch's intra-op threads and OpenBLAS's own pool, which
// torch::set_num_threads does not reach (in the prototype,
// OPENBLAS_NUM_THREADS=1 made batch-256 MLP training 4.5x faster on a
// loaded machine, and 2 torch threads were slower than 1 at batch 128).
void setComputeThreads(int threads);
// Flushes denormal floats to zero (FTZ/DAZ) in this thread and the threads it
// starts afterwards (they inherit the floating-point environment). Why: a
// state-mode BC run slows down as it trains, as denormals appear in its
// weights and Adam's moments: the door's MLP without --normalize-state went
// from 350 iterations/s fresh to 36 at 75k iterations (resumed alone from
// that checkpoint: 36-40 it/s), and FTZ/DAZ restores the fresh speed. For
// training only: the policy plugin runs inside the environment's process,
// whose physics must not change with the policy.
void setFlushDenormals();
// Keeps freed memory in the process for the next allocation instead of
// handing it back to the kernel (glibc: no mmap for large blocks, no trim of
// the heap's top). Why: a point-cloud batch's activations are
// hundreds of MB per tensor (128 clouds x 1200 points x 512 floats: 315 MB),
// which glibc mmaps and unmaps on every allocation, so every iteration
// page-faulted them in afresh. PointNet + Transformer BC on one thread,
// on a loaded 2-core machine: 22 s of its 61 s of CPU went to the kernel;
// kept, 1.9 of 44 s, and 0.128 -> 0.189 iterations/s, the same losses. The
// cost: the process keeps its peak (2.6 -> 3.5 GB resident there). It is
// process-wide: training processes, and a process that
// loads an inference policy (loadInferencePolicy: the torch_policy
// plugin's environment or policy process), where the networks' activations
// otherwise cost more in page faults than in arithmetic; it changes no
// value, only where freed memory goes.
void setKeepFreedMemory();
// What a training process (the trainers and the learning bench, which must
// time what they run) sets before it builds a network: the threads, flushed
// denormals and kept freed memory, above.
void setUpTrainingCompute(int threads);
ComputeInfo calcComputeInfo();
// "BLAS: OpenBLAS 0.3.21 (…/openblas-pthread/libblas.so.3), 1 thread; libtorch 1.13.1: 1 intra-op thread; device cpu"
std::string describeCompute(const ComputeInfo& info, const torch::Device& device);
// "cpu", "cuda" or "cuda:N"; cuda when this libtorch has no CUDA is an
// error saying so (Debian's libtorch is CPU-only).
torch::Device parseDevice(const std::string& name);

}  // namespace manibench::learning
