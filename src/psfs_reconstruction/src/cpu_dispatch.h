// Private: run-time kernel selection and thread-count resolution shared by the .cpp files.
#pragma once

#include <omp.h>

#include "psfs_reconstruction/simd_dispatch.h"

#if (defined(__x86_64__) || defined(__i386__)) && (defined(__GNUC__) || defined(__clang__))
#define PSFS_HAVE_X86_DISPATCH 1
#else
#define PSFS_HAVE_X86_DISPATCH 0
#endif

namespace psfs {

inline bool cpuHasAvx2() { return vectorKernelsActive(); }

// OpenMP thread count for a `threads` option: > 0 as given, 0 = OpenMP's default.
inline int resolveThreads(int threads) { return threads > 0 ? threads : omp_get_max_threads(); }

}  // namespace psfs
