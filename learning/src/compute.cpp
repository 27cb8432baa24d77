#include <manibench/learning/compute.hpp>
#include <manibench/learning/spec.hpp>

#include <dlfcn.h>
#include <malloc.h>

#include <climits>
#include <cstdlib>
#include <sstream>

namespace manibench::learning {

namespace {

// The BLAS libtorch links (libblas.so.3 through Debian's alternatives), as
// already loaded: RTLD_NOLOAD finds it whether it was loaded globally (an
// executable linking libtorch) or inside a dlopen'ed library's group.
void* findBlas() {
  for (const char* name : {"libblas.so.3", "libopenblas.so.0"})
    if (void* handle = dlopen(name, RTLD_LAZY | RTLD_NOLOAD)) return handle;
  return nullptr;
}

}  // namespace

void setComputeThreads(int threads) {
  if (threads < 1) throw LearningError("the thread count must be at least 1");
  torch::set_num_threads(threads);
  if (void* blas = findBlas()) {
    using SetThreads = void (*)(int);
    if (auto set = reinterpret_cast<SetThreads>(dlsym(blas, "openblas_set_num_threads"))) set(threads);
    dlclose(blas);
  }
}

void setFlushDenormals() {
  // False on a CPU without DAZ: nothing to set there; training only runs slower.
  at::globalContext().setFlushDenormal(true);
}

void setKeepFreedMemory() {
  mallopt(M_MMAP_MAX, 0);
  // -1: never trim (mallopt(3)). The largest threshold an int names, 2 GiB,
  // was not enough: BCQ's target pass over 10 sampled actions per transition
  // (640 clouds at batch 64) frees more than that at once, and its process
  // still spent 40 % of its CPU time in the kernel.
  mallopt(M_TRIM_THRESHOLD, -1);
}

void setUpTrainingCompute(int threads) {
  setComputeThreads(threads);
  setFlushDenormals();
  setKeepFreedMemory();
}

ComputeInfo calcComputeInfo() {
  ComputeInfo info;
  info.torch_threads = torch::get_num_threads();
  info.torch_version = TORCH_VERSION;
  info.cuda_available = torch::cuda::is_available();
  void* blas = findBlas();
  if (blas == nullptr) {
    info.blas = "unknown (libblas.so.3 is not loaded)";
    return info;
  }
  if (void* gemm = dlsym(blas, "sgemm_")) {
    Dl_info where;
    if (dladdr(gemm, &where) && where.dli_fname) {
      char resolved[PATH_MAX];
      info.blas_library = realpath(where.dli_fname, resolved) ? resolved : where.dli_fname;
    }
  }
  using GetConfig = char* (*)();
  using GetThreads = int (*)();
  if (auto config = reinterpret_cast<GetConfig>(dlsym(blas, "openblas_get_config"))) {
    info.blas = config();
    if (auto threads = reinterpret_cast<GetThreads>(dlsym(blas, "openblas_get_num_threads")))
      info.blas_threads = threads();
  } else if (info.blas_library.find("/blas/") != std::string::npos) {
    info.blas = "reference BLAS (libblas3)";
    info.blas_is_reference = true;
  } else {
    info.blas = "a BLAS other than OpenBLAS";
  }
  dlclose(blas);
  return info;
}

std::string describeCompute(const ComputeInfo& info, const torch::Device& device) {
  std::ostringstream out;
  out << "BLAS: " << info.blas;
  if (!info.blas_library.empty()) out << " (" << info.blas_library << ")";
  if (info.blas_threads) out << ", " << info.blas_threads << (info.blas_threads == 1 ? " thread" : " threads");
  out << "; libtorch " << info.torch_version << ": " << info.torch_threads
      << (info.torch_threads == 1 ? " intra-op thread" : " intra-op threads") << "; device " << device.str();
  if (info.blas_is_reference)
    out << "\nwarning: the reference BLAS is about 20x slower than OpenBLAS for these networks; "
           "install libopenblas0-pthread (scripts/install-deps does)";
  return out.str();
}

torch::Device parseDevice(const std::string& name) {
  if (name == "cpu") return torch::Device(torch::kCPU);
  if (name == "cuda" || name.rfind("cuda:", 0) == 0) {
    if (!torch::cuda::is_available())
      throw LearningError("--device " + name + ": this libtorch (" + std::string(TORCH_VERSION) +
                          ") has no CUDA or sees no GPU (Debian's libtorch is CPU-only; configure "
                          "with -DCMAKE_PREFIX_PATH=/path/to/a/CUDA/libtorch, docs/learning.md)");
    return torch::Device(name);
  }
  throw LearningError("unknown device '" + name + "' (cpu, cuda or cuda:N)");
}

}  // namespace manibench::learning
