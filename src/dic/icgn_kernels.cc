// The choice of the IC-GN kernel at run time (icgn_kernels.h).
#include "icgn_kernels.h"

#include <atomic>
#include <cstdlib>
#include <string>

#include "impactdic/core/error.h"

namespace impactdic::internal {
namespace {

// The environment variable that forces a kernel.
constexpr const char* kKernelVariable = "IMPACTDIC_DIC_KERNEL";

// The library's kernel of that kind, or nullptr if the compiler could not build it
// (IMPACTDIC_DIC_HAS_<KIND>: src/dic/CMakeLists.txt).
const IcgnKernel* Compiled(DicKernel kernel) {
  switch (kernel) {
    case DicKernel::kScalar: return scalar::Kernel();
    case DicKernel::kAvx2:
#if IMPACTDIC_DIC_HAS_AVX2
      return avx2::Kernel();
#else
      return nullptr;
#endif
    case DicKernel::kAvx512:
#if IMPACTDIC_DIC_HAS_AVX512
      return avx512::Kernel();
#else
      return nullptr;
#endif
  }
  return nullptr;
}

// Whether the CPU runs the kernel's instructions (and the operating system saves their
// registers: __builtin_cpu_supports checks both).
bool CpuRuns(DicKernel kernel) {
  switch (kernel) {
    case DicKernel::kScalar: return true;
    case DicKernel::kAvx2:
#if defined(__x86_64__) || defined(__i386__)
      return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
#else
      return false;
#endif
    case DicKernel::kAvx512:
#if defined(__x86_64__) || defined(__i386__)
      return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
             __builtin_cpu_supports("avx512vl") && CpuRuns(DicKernel::kAvx2);
#else
      return false;
#endif
  }
  return false;
}

constexpr DicKernel kAllKernels[] = {DicKernel::kScalar, DicKernel::kAvx2, DicKernel::kAvx512};

// The kernel IMPACTDIC_DIC_KERNEL names, else the best available one.
const IcgnKernel* Choose() {
  const char* forced = std::getenv(kKernelVariable);
  if (forced != nullptr && *forced != '\0') {
    for (const DicKernel kernel : kAllKernels) {
      if (std::string(forced) != ToString(kernel)) continue;
      if (Compiled(kernel) == nullptr) {
        throw Error(ErrorKind::kInvalidValue, kKernelVariable, forced,
                    "a kernel this build of the library holds (the compiler could not build " +
                        std::string(forced) + ")");
      }
      if (!CpuRuns(kernel)) {
        throw Error(
            ErrorKind::kInvalidValue, kKernelVariable, forced,
            "a kernel this CPU can run (it lacks the " + std::string(forced) + " instructions)");
      }
      return Compiled(kernel);
    }
    throw Error(ErrorKind::kInvalidValue, kKernelVariable, forced, "scalar, avx2 or avx512");
  }
  const IcgnKernel* best = Compiled(DicKernel::kScalar);
  for (const DicKernel kernel : kAllKernels) {
    if (DicKernelAvailable(kernel)) best = Compiled(kernel);
  }
  return best;
}

// The kernel in use (nullptr until the first ActiveIcgnKernel()).
std::atomic<const IcgnKernel*> active{nullptr};

}  // namespace

const char* ToString(DicKernel kernel) {
  switch (kernel) {
    case DicKernel::kScalar: return "scalar";
    case DicKernel::kAvx2: return "avx2";
    case DicKernel::kAvx512: return "avx512";
  }
  return "?";
}

bool DicKernelAvailable(DicKernel kernel) { return Compiled(kernel) != nullptr && CpuRuns(kernel); }

const IcgnKernel& ActiveIcgnKernel() {
  const IcgnKernel* kernel = active.load(std::memory_order_acquire);
  if (kernel == nullptr) {
    // Threads racing here all choose the same kernel; a bad IMPACTDIC_DIC_KERNEL throws on every
    // call.
    kernel = Choose();
    active.store(kernel, std::memory_order_release);
  }
  return *kernel;
}

ScopedIcgnKernelForTesting::ScopedIcgnKernelForTesting(DicKernel kernel)
    : previous_(&ActiveIcgnKernel()) {
  CheckValue(DicKernelAvailable(kernel), "ScopedIcgnKernelForTesting", ToString(kernel),
             "an available kernel");
  active.store(Compiled(kernel), std::memory_order_release);
}

ScopedIcgnKernelForTesting::~ScopedIcgnKernelForTesting() {
  active.store(previous_, std::memory_order_release);
}

}  // namespace impactdic::internal
