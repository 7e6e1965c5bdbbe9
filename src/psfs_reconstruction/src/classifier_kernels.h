// Private row kernels shared by the background model and the pixel classifier. Written as
// plain loops over contiguous float rows without branches or library calls so that GCC/Clang
// auto-vectorise them at -O3 (and again for AVX2/SSE4.1 via PSFS_TARGET_CLONES); kept in one
// place so the learning, update and classification paths convert colours identically.
// Build with -fno-trapping-math -fno-math-errno: without them GCC keeps the float selects
// (a < b ? x : y) and std::sqrt as branches and leaves these loops scalar (several times
// slower, same results). Nothing here reads floating-point exception flags or errno.
// The loops live in functions whose pointer parameters are __restrict: GCC ignores restrict
// on local pointers, and the alias checks it would need instead exceed its limit.
#pragma once

#include <cstdint>
#include <cstring>

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

// exp(-x) for x >= 0 (x is clamped to [0, 87]), relative error < 4e-6: 2^t = 2^i * 2^f with
// i = trunc(t), f in (-1, 0] and a degree-4 polynomial for 2^f (relative least-squares fit on
// [-1, 0]). Branch-free and vectorisable, where std::exp is a library call that blocks
// vectorisation. The output needs 1/255; P = 1/(1 + e) moves by < 1e-6 for this error.
PSFS_ALWAYS_INLINE float expNeg(float x) {
  x = x < 0.0f ? 0.0f : (x > 87.0f ? 87.0f : x);
  const float t = -x * 1.4426950408889634f;  // log2(e)
  const int i = int(t);                      // trunc towards 0 = ceil for t <= 0
  const float f = t - float(i);              // (-1, 0]
  const float p =
      1.0f + f * (0.69306009f + f * (0.23943884f + f * (0.053195773f + f * 0.0068184414f)));
  const std::int32_t bits = (i + 127) << 23;  // 2^i, i >= -126 so always a normal float
  float scale;
  std::memcpy(&scale, &bits, sizeof(scale));
  return p * scale;
}

// One interleaved rgb8 row -> normalised r, g and intensity I = (R+G+B)/3 (color_space.h).
// Black pixels get the grey point (1/3, 1/3), as toNormalizedRgI() does.
PSFS_ALWAYS_INLINE void rgbRowToRgI(const std::uint8_t* __restrict rgb, int n, float* __restrict r,
                                    float* __restrict g, float* __restrict intensity) {
  for (int x = 0; x < n; ++x) {
    const float R = float(rgb[3 * x]), G = float(rgb[3 * x + 1]), B = float(rgb[3 * x + 2]);
    const float s = R + G + B;
    const float inv = 1.0f / (s > 0.0f ? s : 1.0f);
    r[x] = s > 0.0f ? R * inv : (1.0f / 3.0f);
    g[x] = s > 0.0f ? G * inv : (1.0f / 3.0f);
    intensity[x] = s * (1.0f / 3.0f);
  }
}

}  // namespace kernels
}  // namespace psfs
