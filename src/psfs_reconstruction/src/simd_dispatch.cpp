#include "psfs_reconstruction/simd_dispatch.h"

#include <atomic>
#include <cstdlib>
#include <cstring>

#include "cpu_dispatch.h"
#include "psfs_kernels.h"

namespace psfs {
namespace {
// TABLETOP_SIMD=avx2 or =scalar starts the process with those kernels, e.g. to run the suite or
// the demo as on a machine without AVX-512 (or without AVX2); the force*() calls override it.
bool simdEnvIs(const char* value) {
  const char* e = std::getenv("TABLETOP_SIMD");
  return e != nullptr && std::strcmp(e, value) == 0;
}
std::atomic<bool> g_force_scalar{simdEnvIs("scalar")};
std::atomic<bool> g_force_avx2{simdEnvIs("avx2")};

bool detectAvx512() {
#if PSFS_HAVE_X86_DISPATCH
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw") &&
         __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
#else
  return false;
#endif
}

bool detectAvx2() {
#if PSFS_HAVE_X86_DISPATCH
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
#else
  return false;
#endif
}
}  // namespace

bool avx2Available() {
  static const bool available = detectAvx2();
  return available;
}

void forceScalarKernels(bool force) { g_force_scalar.store(force); }

bool scalarKernelsForced() { return g_force_scalar.load(std::memory_order_relaxed); }

bool vectorKernelsActive() { return avx2Available() && !g_force_scalar.load(std::memory_order_relaxed); }

bool avx512Available() {
  static const bool available = detectAvx512();
  return available;
}

void forceAvx2Kernels(bool force) { g_force_avx2.store(force); }

bool avx512KernelsActive() {
  return vectorKernelsActive() && avx512Available() && !g_force_avx2.load(std::memory_order_relaxed);
}

int64_t highwayTarget() { return detail::hwyRowTarget(!scalarKernelsForced(), avx512KernelsActive()); }

size_t highwayDispatchIndex(int64_t target) { return detail::hwyDispatchIndex(target); }

}  // namespace psfs
