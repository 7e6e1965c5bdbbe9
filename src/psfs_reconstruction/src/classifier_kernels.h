// Private row kernels shared by the background model and the pixel classifier. Written as
// plain loops over contiguous float rows without branches or library calls so that GCC/Clang
// auto-vectorise them at -O3 (and again for AVX2/SSE4.1 via PSFS_TARGET_CLONES); kept in one
// place so the learning, update and classification paths convert colours identically. The
// per-pixel arithmetic itself is in pixel_arithmetic.h, shared with the CUDA kernels.
// Build with -fno-trapping-math -fno-math-errno: without them GCC keeps the float selects
// (a < b ? x : y) and std::sqrt as branches and leaves these loops scalar (several times
// slower, same results). Nothing here reads floating-point exception flags or errno.
// The loops live in functions whose pointer parameters are __restrict: GCC ignores restrict
// on local pointers, and the alias checks it would need instead exceed its limit.
#pragma once

#include <cstdint>

#include "pixel_arithmetic.h"

namespace psfs {
namespace kernels {

// Compiles a function three times (AVX2, SSE4.1, baseline x86-64) and lets the loader pick
// the best for the CPU (GCC/Clang function multiversioning, ifunc), so the package needs no
// -march flag. Baseline SSE2 cannot vectorise the stride-3 rgb8 loads; SSE4.1 can, AVX2 does
// 8 pixels per step. FMA is deliberately not enabled: every clone does the same IEEE
// operations in the same order, so all CPUs produce identical likelihood images.
#if defined(__x86_64__) && defined(__linux__) && (defined(__GNUC__) || defined(__clang__)) && \
    !defined(PSFS_NO_TARGET_CLONES)
#define PSFS_TARGET_CLONES __attribute__((target_clones("avx2", "sse4.1", "default")))
#else
#define PSFS_TARGET_CLONES
#endif
// Row helpers are inlined into the multiversioned row function so they get its instruction set.
#if defined(__GNUC__) || defined(__clang__)
#define PSFS_ALWAYS_INLINE inline __attribute__((always_inline))
#else
#define PSFS_ALWAYS_INLINE inline
#endif

// One interleaved rgb8 row -> normalised r, g and intensity I = (R+G+B)/3 (color_space.h).
// Black pixels get the grey point (1/3, 1/3), as toNormalizedRgI() does.
PSFS_ALWAYS_INLINE void rgbRowToRgI(const std::uint8_t* __restrict rgb, int n, float* __restrict r,
                                    float* __restrict g, float* __restrict intensity) {
  for (int x = 0; x < n; ++x) {
    const pixel::RgI c = pixel::rgbToRgI(rgb[3 * x], rgb[3 * x + 1], rgb[3 * x + 2]);
    r[x] = c.r;
    g[x] = c.g;
    intensity[x] = c.intensity;
  }
}

}  // namespace kernels
}  // namespace psfs
